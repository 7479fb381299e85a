#pragma once

#include <ff/storage/SceneFormat.h>
#include <ff/storage/Status.h>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <span>
#include <vector>

namespace ff::builder {

/**
 * An append-only temporary file of PackedTriangles with its own write buffer: how the builder
 * keeps triangle streams out of memory. Reading is sequential, in batches. The file is removed
 * when the RunFile dies. Not thread-safe.
 */
class RunFile {
public:
    explicit RunFile(std::filesystem::path path);
    ~RunFile();
    RunFile(RunFile&& other) noexcept;
    RunFile& operator=(RunFile&&) = delete;
    RunFile(const RunFile&) = delete;
    RunFile& operator=(const RunFile&) = delete;

    /** Buffers `triangles`; writes through once the buffer holds `bufferLimitBytes`. */
    [[nodiscard]] Status append(std::span<const storage::PackedTriangle> triangles);
    /** Writes the buffer out (opening/closing the file, so many RunFiles cost no descriptors). */
    [[nodiscard]] Status flush();

    std::uint64_t count() const noexcept { return mCount; }
    std::size_t bufferedBytes() const noexcept { return mBuffer.size() * sizeof(storage::PackedTriangle); }
    std::uint64_t bytesWritten() const noexcept { return mBytesWritten; }
    const std::filesystem::path& path() const noexcept { return mPath; }

    void setBufferLimit(std::size_t bytes) noexcept { mBufferLimitBytes = bytes; }

    /** Flushes, then calls visit() on consecutive batches of at most batchSize triangles. */
    [[nodiscard]] Status forEachBatch(
            std::size_t batchSize,
            const std::function<Status(std::span<const storage::PackedTriangle>)>& visit);

    /** Flushes, then reads the whole file. */
    [[nodiscard]] Result<std::vector<storage::PackedTriangle>> readAll();

    /** Deletes the file and forgets its contents. */
    void remove() noexcept;

private:
    std::filesystem::path mPath;
    std::vector<storage::PackedTriangle> mBuffer;
    std::size_t mBufferLimitBytes = 1u << 20;
    std::uint64_t mCount = 0;
    std::uint64_t mBytesWritten = 0;
    bool mCreated = false;
};

/** ENOSPC/EDQUOT become DiskFull, anything else IoError; the message names the path. */
Status ioStatus(int error, const std::string& what, const std::filesystem::path& path);

} // namespace ff::builder
