#pragma once

// Page access, source layer: the IPageSource of a scene file on a local disk.

#include <ff/cache/PageCache.h>
#include <ff/storage/Status.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>

namespace ff::cache {

/**
 * The pages of one scene file (.ffs) on a local disk, read with pread() from the source's own
 * descriptor (no mapping) and verified exactly as storage::SceneFile verifies them (trailer
 * magic, XXH3-64 checksum, page index; storage::verifyPageBytes). The page type is not checked:
 * the reader of the bytes knows what it expects. storage::SceneIndex::read() reads the scene's
 * header and tables through it.
 *
 * Thread-safety: readPage() may be called from any number of threads at once (pread does not
 * move a shared file offset); the other methods are const and immutable after open().
 */
class ScenePageSource final : public IPageSource {
public:
    /** Opens `path` and learns its page layout from the header page (storage::probePageSize,
     *  storage::checkPageLayout: magic, version, page size, checksum, page count against the
     *  file's size). Errors: NotFound, IoError (naming the path), Corrupt "page N: ...",
     *  Unsupported: as storage::SceneFile::open words them. */
    [[nodiscard]] static Result<std::unique_ptr<ScenePageSource>>
    open(const std::filesystem::path& path);

    ~ScenePageSource() override;
    ScenePageSource(const ScenePageSource&) = delete;
    ScenePageSource& operator=(const ScenePageSource&) = delete;

    std::uint32_t pageSize() const override;
    std::uint64_t pageCount() const override;
    const std::filesystem::path& path() const noexcept;

    /** Reads page `index` into `out` (exactly pageSize() bytes: asserted) and verifies it.
     *  Errors: Corrupt "page N: ..." (bad trailer or checksum, beyond the end of the file, file
     *  shrunk since open), IoError. `out` holds garbage after an error. */
    [[nodiscard]] Status readPage(std::uint64_t index, std::span<std::byte> out) override;

private:
    ScenePageSource(
            std::filesystem::path path, int fd, std::uint32_t pageSize, std::uint64_t pageCount);
    std::filesystem::path mPath;
    int mFd = -1;
    std::uint32_t mPageSize = 0;
    std::uint64_t mPageCount = 0;
};

} // namespace ff::cache
