#pragma once

#include <ff/storage/PageSource.h>
#include <ff/storage/SceneFormat.h>
#include <ff/storage/SceneIndex.h>
#include <ff/storage/Status.h>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace ff::storage {

struct SceneFileOptions {
    /** Verify every page's checksum at open (what `farfield check` does); else pages are
     *  verified on first access. */
    bool verifyEveryPage = false;
};

/**
 * A scene file read through mmap: its index (SceneIndex, read through the mapping at open) and
 * its pages. Every access is bounds-checked against the file and every page is checksum-verified
 * before its bytes are handed out (once; the result is cached), so corrupt or truncated files
 * produce a Status naming the page, never a crash. Page bytes live in the mapping, valid as long
 * as the SceneFile: pagePayload() hands out views, and pinPage() of source() pins without a
 * copy.
 *
 * Thread-safety: all const methods may be called concurrently.
 */
class SceneFile : public SceneIndex {
public:
    /** Maps the file, checks the header page and reads the prototype, instance and metadata
     *  sections. Errors: NotFound, IoError, Corrupt (with the page number), Unsupported. */
    [[nodiscard]] static Result<std::unique_ptr<SceneFile>> open(
            const std::filesystem::path& path, const SceneFileOptions& options = {});

    ~SceneFile();
    SceneFile(const SceneFile&) = delete;
    SceneFile& operator=(const SceneFile&) = delete;

    const std::filesystem::path& path() const noexcept;

    /** The mapped pages as a page source (verified as verifyPage() verifies them; pins are
     *  views into the mapping). Lives as long as *this. */
    IPageSource& source() const noexcept;

    /** Checks page `index`: in range, trailer index/type/magic, checksum. Cached on success. */
    [[nodiscard]] Status verifyPage(std::uint64_t index, PageType expected) const;

    /** The payload bytes (pagePayloadBytes long) of a verified page; valid while *this lives. */
    [[nodiscard]] Result<std::span<const std::byte>> pagePayload(
            std::uint64_t index, PageType expected) const;

    /** Reads and validates one node record (ranges, kinds, finite bounds). */
    [[nodiscard]] Result<NodeRecord> node(NodeRef ref) const;

    /** The `index`-th child of `parent` (index < parent.childCount). */
    [[nodiscard]] Result<NodeRecord> child(const NodeRecord& parent, std::uint32_t index) const;

    /** Triangles of one segment, from a verified page. */
    [[nodiscard]] Result<std::span<const std::byte>> segmentBytes(const GeometrySegment& s) const;

    /** Verifies every page in file order; the first failure names its page. progress(done,
     *  total) is called now and then if given. */
    [[nodiscard]] Status verifyAll(
            const std::function<void(std::uint64_t, std::uint64_t)>& progress = {}) const;

private:
    struct Impl;
    SceneFile(SceneIndex index, std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> mImpl;
};

} // namespace ff::storage
