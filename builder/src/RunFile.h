#pragma once

#include "PendingNodeV2.h"

#include <ff/builder/SpillCodec.h>
#include <ff/storage/SceneFormat.h>
#include <ff/storage/Status.h>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <span>
#include <vector>

namespace ff::builder {

/**
 * An append-only temporary file of fixed-size records (triangles, node records) with its own
 * write buffer: how the builder keeps streams out of memory. The file is a sequence of blocks
 * of at most kSpillBlockBytes of items each, encoded with the file's codec behind a 16-byte
 * header; reading is sequential, in batches, one decoded block in memory at a time. The file
 * is removed when the SpillFile dies. Not thread-safe.
 */
template <class Item>
class SpillFile {
public:
    explicit SpillFile(std::filesystem::path path, SpillCodec codec = SpillCodec::Compact);
    ~SpillFile();
    SpillFile(SpillFile&& other) noexcept;
    SpillFile& operator=(SpillFile&&) = delete;
    SpillFile(const SpillFile&) = delete;
    SpillFile& operator=(const SpillFile&) = delete;

    /** Buffers `items`; writes the buffer and `items` through once they reach
     *  `bufferLimitBytes` (0: every append writes through). */
    [[nodiscard]] Status append(std::span<const Item> items);
    /** Writes the buffer out (opening/closing the file, so many RunFiles cost no descriptors). */
    [[nodiscard]] Status flush();

    std::uint64_t count() const noexcept { return mCount; }
    std::size_t bufferedBytes() const noexcept { return mBuffer.size() * sizeof(Item); }
    /** Bytes on disk: encoded blocks and their headers. */
    std::uint64_t bytesWritten() const noexcept { return mBytesWritten; }
    SpillCodec codec() const noexcept { return mCodec; }
    const std::filesystem::path& path() const noexcept { return mPath; }

    void setBufferLimit(std::size_t bytes) noexcept { mBufferLimitBytes = bytes; }

    /** Flushes, then calls visit() on consecutive batches of at most batchSize items. */
    [[nodiscard]] Status forEachBatch(
            std::size_t batchSize,
            const std::function<Status(std::span<const Item>)>& visit);

    /**
     * Like forEachBatch(), but gives the disk space of what was visited back as it goes (a
     * hole punched behind the reader, where the file system can) and removes the file at the
     * end, whatever the outcome: a pass that moves the items elsewhere then needs their space
     * once, not twice. Returns the bytes given back before the end (0 where holes are not
     * supported).
     */
    [[nodiscard]] Result<std::uint64_t> consumeBatches(
            std::size_t batchSize,
            const std::function<Status(std::span<const Item>)>& visit);

    /** Flushes, then reads the whole file. */
    [[nodiscard]] Result<std::vector<Item>> readAll();

    /** Deletes the file and forgets its contents. */
    void remove() noexcept;

private:
    /** Writes the buffer, then `more`, and empties the buffer. */
    [[nodiscard]] Status writeOut(std::span<const Item> more);
    /** Appends one block of at most kSpillBlockBytes of items to `fd`. */
    [[nodiscard]] Status writeBlock(int fd, std::span<const Item> items, std::vector<unsigned char>& scratch);
    /** forEachBatch() and consumeBatches(): `afterBatch` gets the descriptor and the bytes read. */
    [[nodiscard]] Status readBatches(
            std::size_t batchSize,
            int openFlags,
            const std::function<Status(std::span<const Item>)>& visit,
            const std::function<void(int fd, std::uint64_t bytesRead)>& afterBatch);

    std::filesystem::path mPath;
    SpillCodec mCodec;
    std::vector<Item> mBuffer;
    std::size_t mBufferLimitBytes = 1u << 20;
    std::uint64_t mCount = 0;
    std::uint64_t mBytesWritten = 0;
    bool mCreated = false;
};

/** Raw bytes of items in one block of a spill file at most: what reading holds decoded. */
inline constexpr std::size_t kSpillBlockBytes = 1u << 20;

/** Triangles on their way to a chunk or a level region (RunFile.cpp instantiates these two). */
using RunFile = SpillFile<storage::PackedTriangle>;
/** Node records on their way to a level region. */
using RecordFile = SpillFile<storage::NodeRecord>;
/** And format 2's (RunFile.cpp instantiates it too). */
using RecordFileV2 = SpillFile<PendingNodeV2>;

/** ENOSPC/EDQUOT become DiskFull, anything else IoError; the message names the path. */
Status ioStatus(int error, const std::string& what, const std::filesystem::path& path);

} // namespace ff::builder
