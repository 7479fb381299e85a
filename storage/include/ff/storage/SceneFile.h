#pragma once

#include <ff/storage/SceneFormat.h>
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

/** A run of one node's triangles inside one Geometry page. */
struct GeometrySegment {
    std::uint64_t page;
    std::uint32_t firstSlot;
    std::uint32_t count;
};

/**
 * Read access to a scene file through mmap. Every access is bounds-checked against the file and
 * every page is checksum-verified before its bytes are handed out (once; the result is cached),
 * so corrupt or truncated files produce a Status naming the page, never a crash.
 *
 * Thread-safety: all const methods may be called concurrently.
 */
class SceneFile {
public:
    /** Maps the file, checks the header page and reads the prototype, instance and metadata
     *  sections. Errors: NotFound, IoError, Corrupt (with the page number), Unsupported. */
    [[nodiscard]] static Result<std::unique_ptr<SceneFile>> open(
            const std::filesystem::path& path, const SceneFileOptions& options = {});

    ~SceneFile();
    SceneFile(const SceneFile&) = delete;
    SceneFile& operator=(const SceneFile&) = delete;

    const FileHeader& header() const noexcept;
    std::span<const SectionEntry> sections() const noexcept;
    std::uint32_t pageSize() const noexcept;
    std::uint64_t pageCount() const noexcept;
    const std::filesystem::path& path() const noexcept;

    /** Checks page `index`: in range, trailer index/type/magic, checksum. Cached on success. */
    [[nodiscard]] Status verifyPage(std::uint64_t index, PageType expected) const;

    /** The payload bytes (pagePayloadBytes long) of a verified page; valid while *this lives. */
    [[nodiscard]] Result<std::span<const std::byte>> pagePayload(
            std::uint64_t index, PageType expected) const;

    /** Reads and validates one node record (ranges, kinds, finite bounds). */
    [[nodiscard]] Result<NodeRecord> node(NodeRef ref) const;

    /** Decodes and validates slot `ref.slot` from the payload of Nodes page `ref.page` that
     *  the caller already holds (e.g. from a page cache); the same checks as node(). */
    [[nodiscard]] Result<NodeRecord> decodeNode(std::span<const std::byte> nodesPagePayload, NodeRef ref) const;

    /** The `index`-th child of `parent` (index < parent.childCount). */
    [[nodiscard]] Result<NodeRecord> child(const NodeRecord& parent, std::uint32_t index) const;

    /** Ref of the `index`-th child of `parent`. */
    static NodeRef childRef(const NodeRecord& parent, std::uint32_t index) noexcept {
        return {parent.firstChild.page, parent.firstChild.slot + index};
    }

    /** Appends the page runs holding `node`'s own triangles to `out` (checked, not verified). */
    [[nodiscard]] Status geometrySegments(
            const NodeRecord& node, std::vector<GeometrySegment>& out) const;

    /** Triangles of one segment, from a verified page. */
    [[nodiscard]] Result<std::span<const std::byte>> segmentBytes(const GeometrySegment& s) const;

    const std::vector<PrototypeRecord>& prototypes() const noexcept;
    const std::vector<InstanceRecord>& instances() const noexcept;
    /** The Metadata section (JSON text), empty if the file has none. */
    const std::string& metadataJson() const noexcept;

    /** Verifies every page in file order; the first failure names its page. progress(done,
     *  total) is called now and then if given. */
    [[nodiscard]] Status verifyAll(
            const std::function<void(std::uint64_t, std::uint64_t)>& progress = {}) const;

private:
    struct Impl;
    explicit SceneFile(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> mImpl;
};

} // namespace ff::storage
