#pragma once

// The scene index: what a reader must know before it reads any node — the header, the section
// table, prototypes, instances and metadata — read through an IPageSource like every other page,
// so a file, a range server or object storage serve it alike. Node records and triangle runs are
// decoded by free-standing, bounds-checked functions over page bytes the caller holds, wherever
// they came from (a mapping, the page cache). FORMAT.md §9 lists the rules.

#include <ff/storage/PageSource.h>
#include <ff/storage/PrototypeRecordV2.h>
#include <ff/storage/SceneFormat.h>
#include <ff/storage/Status.h>

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace ff::storage {

/** How a file is cut into pages, as its header says and its size confirms. */
struct PageLayout {
    std::uint32_t pageSize = 0;
    std::uint64_t pageCount = 0;
};

/**
 * Opening a file, step 1: the page size, from the file's first bytes (`start`: up to
 * sizeof(FileHeader) are looked at; fewer only when the file is that short) and the file's size.
 * Magic and version come first and never move, so a future version is recognised as such
 * before anything else is trusted. Errors: Corrupt "page 0: ..." (bad magic, invalid page size,
 * truncated), Unsupported (another format version).
 */
[[nodiscard]] Result<std::uint32_t>
probePageSize(std::span<const std::byte> start, std::uint64_t fileSize);

/**
 * Opening a file, step 2: with page 0 whole (probePageSize() bytes), verifies it (trailer,
 * checksum, a Header page) and checks the page count against the file's size. Errors: Corrupt
 * "page N: ..." naming the first missing or extra page.
 */
[[nodiscard]] Result<PageLayout>
checkPageLayout(std::span<const std::byte> page0, std::uint64_t fileSize);

/** A run of one node's triangles inside one Geometry page. */
struct GeometrySegment {
    std::uint64_t page;
    std::uint32_t firstSlot;
    std::uint32_t count;
};

/**
 * The header and tables of one scene file, checked (FORMAT.md §9.1: struct sizes, section
 * table, root, origin, every prototype and instance). Immutable after read(); every method is
 * const and safe to call from several threads at once.
 */
class SceneIndex {
public:
    /** Reads page 0 and the table sections through `source` (whose page size and count come
     *  from probePageSize() and checkPageLayout()). Errors: Corrupt "page N: ...", Unsupported,
     *  IoError (the source's). */
    [[nodiscard]] static Result<SceneIndex> read(IPageSource& source);

    const FileHeader& header() const noexcept { return mHeader; }
    std::span<const SectionEntry> sections() const noexcept { return mSections; }
    std::uint32_t pageSize() const noexcept { return mHeader.pageSize; }
    std::uint64_t pageCount() const noexcept { return mHeader.pageCount; }
    /** kFormatVersion or kFormatVersion2. */
    std::uint32_t formatVersion() const noexcept { return mHeader.formatVersion; }
    /** Version 1's prototypes (empty in a version 2 file: prototypesV2()). */
    const std::vector<PrototypeRecord>& prototypes() const noexcept { return mPrototypes; }
    /** Version 2's prototypes, grids included (empty in a version 1 file). */
    const std::vector<PrototypeV2>& prototypesV2() const noexcept { return mPrototypesV2; }
    std::uint64_t prototypeCount() const noexcept;
    /** Version 2: the file page of each Nodes page, in node-index order (the NodePages section). */
    const std::vector<std::uint32_t>& nodePages() const noexcept { return mNodePages; }
    /** Version 2: node indices the NodePages section spans (pages x nodesPerPageV2). */
    std::uint64_t nodeSlotCount() const noexcept { return mNodePages.size() * std::uint64_t{mNodesPerPage}; }
    /** Version 2: the page and slot of node `nodeIndex`. Errors: Corrupt outside the node slots. */
    [[nodiscard]] Result<NodeRef> nodeLocation(std::uint32_t nodeIndex) const;
    const std::vector<InstanceRecord>& instances() const noexcept { return mInstances; }
    /** The Metadata section (JSON text), empty if the file has none. */
    const std::string& metadataJson() const noexcept { return mMetadata; }

    /** Version 1: decodes and validates slot `ref.slot` of Nodes page `ref.page`, whose payload
     *  the caller holds (a mapping, a page cache): kind, flags, finite and ordered boxes,
     *  children and triangle runs inside the file, instance index in range. Version 2 files'
     *  nodes are read with readNodeV2 (Unsupported here). */
    [[nodiscard]] Result<NodeRecord>
    decodeNode(std::span<const std::byte> nodesPagePayload, NodeRef ref) const;

    /** Ref of the `index`-th child of `parent`. */
    static NodeRef childRef(const NodeRecord& parent, std::uint32_t index) noexcept {
        return {parent.firstChild.page, parent.firstChild.slot + index};
    }

    /** Appends the page runs holding `node`'s own triangles to `out` (checked, not read). */
    [[nodiscard]] Status
    geometrySegments(const NodeRecord& node, std::vector<GeometrySegment>& out) const;

    /** The page types the section table allows on page `index` (a Table page inside a table
     *  section, Header for page 0, Nodes or Geometry elsewhere), as a mask of
     *  1 << PageType. */
    [[nodiscard]] std::uint32_t allowedPageTypes(std::uint64_t index) const noexcept;

protected:
    SceneIndex() = default;

private:
    Status readHeader(std::span<const std::byte> page0);
    Status readTables(IPageSource& source);
    Status
    readStream(IPageSource& source, const SectionEntry& s, std::vector<std::byte>& out) const;
    std::uint64_t streamPage(const SectionEntry& s, std::uint64_t offset) const noexcept;
    /** Where the section's stream starts in its first page (v2's offset; 0 in v1). */
    std::uint64_t streamOffset(const SectionEntry& s) const noexcept;
    bool nodeRefInFile(NodeRef ref) const noexcept;
    Status checkRootsV2() const;
    /** Why a Cell's triangle run leaves the file, or empty if it stays inside. */
    std::string geometryRunProblem(const NodeRecord& node) const;

    FileHeader mHeader{};
    std::vector<SectionEntry> mSections;
    std::vector<PrototypeRecord> mPrototypes;
    std::vector<PrototypeV2> mPrototypesV2;
    std::vector<std::uint32_t> mNodePages;
    std::vector<InstanceRecord> mInstances;
    std::string mMetadata;
    std::uint32_t mNodesPerPage = 0;
    std::uint32_t mTrianglesPerPage = 0;
};

} // namespace ff::storage
