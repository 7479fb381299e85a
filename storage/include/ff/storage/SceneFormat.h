#pragma once

// The on-disk layout of a farfield scene file (.ffs). storage/FORMAT.md documents every byte;
// this header is its executable form. All integers are little-endian, all floats IEEE-754
// binary32. Structs here are copied in and out of pages with memcpy, never cast in place.
//
// Version history:
//   1  first format: header page + section table, node pages, geometry pages, table pages;
//      16-byte trailer with XXH3-64 checksum on every page.
//   2  compact: 48-byte node records addressed by node index through a NodePages section, each
//      node's representations in its Nodes page, geometry pages of clusters (ClusterPage.h),
//      64-byte prototype records with the position grid. Written by `build --format 2`;
//      storage reads and checks it, the runtime draws it.

#include <array>
#include <cstddef>
#include <cstdint>

namespace ff::storage {

inline constexpr std::array<char, 8> kFileMagic = {'F', 'F', 'S', 'C', 'E', 'N', 'E', '\0'};
inline constexpr std::uint32_t kFormatVersion = 1;
inline constexpr std::uint32_t kFormatVersion2 = 2;

inline constexpr std::uint32_t kMinPageSize = 4096;
inline constexpr std::uint32_t kMaxPageSize = 16u << 20;
inline constexpr std::uint32_t kDefaultPageSize = 64u << 10;

/** What a page holds; stored in its trailer so a misplaced page is detected. */
enum class PageType : std::uint16_t {
    Header = 1,   ///< page 0: FileHeader + SectionEntry table
    Nodes = 2,    ///< NodeRecord slots
    Geometry = 3, ///< PackedTriangle slots
    Table = 4,    ///< byte stream of a section (prototypes, instances, metadata)
};

inline constexpr std::uint16_t kPageTrailerMagic = 0xFF5C;

/**
 * Last 16 bytes of every page. `checksum` is XXH3-64 (seed 0) of the page's first
 * pageSize - 8 bytes, i.e. the payload and the first three trailer fields.
 */
struct PageTrailer {
    std::uint32_t pageIndex; ///< the page's own index: catches pages written to the wrong place
    std::uint16_t pageType;  ///< a PageType
    std::uint16_t magic;     ///< kPageTrailerMagic
    std::uint64_t checksum;
};
static_assert(sizeof(PageTrailer) == 16);

/** Bytes of a page available to its payload. */
constexpr std::uint32_t pagePayloadBytes(std::uint32_t pageSize) noexcept {
    return pageSize - static_cast<std::uint32_t>(sizeof(PageTrailer));
}

/** Sections whose data lives in Table pages (or, for Hierarchy, names a page range). */
enum class SectionType : std::uint32_t {
    Prototypes = 1, ///< PrototypeRecord[itemCount]
    Instances = 2,  ///< InstanceRecord[itemCount]
    Metadata = 3,   ///< UTF-8 JSON: scene description and build report
    Hierarchy = 4,  ///< the range of Nodes and Geometry pages (no byte stream; byteLength 0)
    NodePages = 5,  ///< v2: u32[itemCount], the file page of each Nodes page, in node-index order
};

/** v2 header flags (v1 has none). */
enum FileFlagsV2 : std::uint32_t {
    kFileV2HasRoot = 1u << 0, ///< `root.page` is the node index of the instance level's root
};

/**
 * One entry of the section table in page 0. For table sections the bytes form one stream over
 * pages [firstPage, firstPage + pageCount): logical byte i lives in page firstPage + i / P at
 * offset i % P, with P = pagePayloadBytes(pageSize) (v2: shifted by `offset`).
 */
struct SectionEntry {
    std::uint32_t type; ///< a SectionType
    /** v1: reserved (0). v2: the payload offset in firstPage where a table section's stream
     *  starts, so small sections share a page: byte i lives in page firstPage + (offset + i) / P
     *  at (offset + i) % P. */
    std::uint32_t offset;
    std::uint64_t firstPage;
    std::uint64_t pageCount;
    std::uint64_t byteLength;
    std::uint64_t itemCount;
};
static_assert(sizeof(SectionEntry) == 40);

/** Points at one NodeRecord: slot `slot` of Nodes page `page`. */
struct NodeRef {
    std::uint32_t page;
    std::uint32_t slot;

    friend bool operator==(const NodeRef&, const NodeRef&) = default;
};
static_assert(sizeof(NodeRef) == 8);

inline constexpr NodeRef kNullNodeRef = {0, 0}; // page 0 is the header: never a node page

/** Starts page 0. The SectionEntry table follows at offset sizeof(FileHeader). */
struct FileHeader {
    std::array<char, 8> magic; ///< kFileMagic
    std::uint32_t formatVersion;
    std::uint32_t pageSize; ///< power of two in [kMinPageSize, kMaxPageSize]
    std::uint64_t pageCount; ///< file size is exactly pageCount * pageSize
    // Struct sizes, so a reader can refuse a file written with a different layout.
    std::uint32_t headerSize;
    std::uint32_t sectionEntrySize;
    std::uint32_t nodeRecordSize;
    std::uint32_t triangleSize;
    std::uint32_t prototypeRecordSize;
    std::uint32_t instanceRecordSize;
    std::uint32_t sectionCount; ///< entries in the table after this header
    std::uint32_t flags;        ///< reserved, 0
    NodeRef root;               ///< the scene's root node (instance level)
    std::array<float, 3> boundsMin; ///< bounds of everything drawn, in the file's frame
    std::array<float, 3> boundsMax;
    std::uint64_t nodeCount;          ///< NodeRecords in the file
    std::uint64_t storedTriangles;    ///< PackedTriangles in the file (prototypes counted once)
    std::uint64_t instancedTriangles; ///< triangles as drawn (each instance counted)
    /** World position of the file frame's origin: world = origin + stored coordinates. Kept in
     *  double so a scene far from the world origin keeps float precision in its own frame. */
    std::array<double, 3> origin;
    std::array<std::uint8_t, 24> reserved;
};
static_assert(sizeof(FileHeader) == 160);

/** 0 = -X, 1 = +X, 2 = -Y, 3 = +Y, 4 = -Z, 5 = +Z: face f lies on axis f/2, side f%2. */
inline constexpr int kCubeFaceCount = 6;

/** Node kinds. */
enum class NodeKind : std::uint8_t {
    Cell = 0,     ///< a spatial cell: children and/or its own triangles
    Instance = 1, ///< an instance: geometryPage holds the instance index; descends into its prototype
};

enum NodeFlags : std::uint8_t {
    kNodeHasCube = 1u << 0,        ///< `cube` holds a baked color cube
    kNodeOctreeChildren = 1u << 1, ///< children are octant cells of this cell (or instances in them)
};

/**
 * One hierarchy node, 96 bytes, in a slot of a Nodes page. Children of a node are `childCount`
 * consecutive slots starting at `firstChild`, always inside one page.
 */
struct NodeRecord {
    std::array<float, 3> cellMin; ///< the box whose faces carry the color cube
    std::array<float, 3> cellMax;
    std::array<float, 3> boundsMin; ///< tight bounds of everything below (culling, ε rule)
    std::array<float, 3> boundsMax;
    /** Color cube: premultiplied linear RGBA8 per face, faces in kCubeFace order. */
    std::array<std::array<std::uint8_t, 4>, kCubeFaceCount> cube;
    NodeRef firstChild;
    std::uint8_t childCount;
    std::uint8_t kind;   ///< a NodeKind
    std::uint8_t level;  ///< depth below the root of its own hierarchy (prototype or instance level)
    std::uint8_t flags;  ///< NodeFlags
    /** Cell: triangles start at slot geometryFirst of Geometry page geometryPage and run on
     *  through the following pages. Instance: geometryPage is the instance index. */
    std::uint32_t geometryPage;
    std::uint32_t geometryFirst;
    std::uint32_t geometryCount; ///< this node's own triangles (not its children's)
};
static_assert(sizeof(NodeRecord) == 96);

/** Vertex as drawn: position, octahedral-encoded normal (snorm16), sRGB8 colour + alpha. */
struct PackedVertex {
    std::array<float, 3> position;
    std::array<std::int16_t, 2> normalOct;
    std::array<std::uint8_t, 4> color; ///< sRGB-encoded RGB, linear alpha (1 = opaque)
};
static_assert(sizeof(PackedVertex) == 20);

struct PackedTriangle {
    std::array<PackedVertex, 3> vertices;
};
static_assert(sizeof(PackedTriangle) == 60);

/** A prototype: a mesh stored once, drawn by any number of instances. */
struct PrototypeRecord {
    NodeRef root;
    std::array<float, 3> boundsMin;
    std::array<float, 3> boundsMax;
    std::uint64_t triangleCount;
    std::uint64_t nodeCount;
};
static_assert(sizeof(PrototypeRecord) == 48);

/** One placement of a prototype. transform is row-major 3x4 (rotation/scale | translation). */
struct InstanceRecord {
    std::array<float, 12> transform;
    std::uint32_t prototype;
    std::uint32_t reserved;
};
static_assert(sizeof(InstanceRecord) == 56);

/** The struct sizes the header of a file of a format version states (its *Size fields): a reader
 *  refuses a file whose fields say otherwise. v2 keeps the field layout; its `triangleSize`
 *  field holds the representation record's size (FORMAT.md §3.1). */
struct StructSizes {
    std::uint32_t header = 0;
    std::uint32_t sectionEntry = 0;
    std::uint32_t nodeRecord = 0;
    std::uint32_t triangleOrRepresentation = 0;
    std::uint32_t prototypeRecord = 0;
    std::uint32_t instanceRecord = 0;
};
constexpr StructSizes structSizesOf(std::uint32_t formatVersion) noexcept {
    if (formatVersion == kFormatVersion2)
        return {sizeof(FileHeader), sizeof(SectionEntry), 48, 20, 64, sizeof(InstanceRecord)};
    return {sizeof(FileHeader),
            sizeof(SectionEntry),
            sizeof(NodeRecord),
            sizeof(PackedTriangle),
            sizeof(PrototypeRecord),
            sizeof(InstanceRecord)};
}

/** Slots per page. */
constexpr std::uint32_t nodesPerPage(std::uint32_t pageSize) noexcept {
    return pagePayloadBytes(pageSize) / static_cast<std::uint32_t>(sizeof(NodeRecord));
}
constexpr std::uint32_t trianglesPerPage(std::uint32_t pageSize) noexcept {
    return pagePayloadBytes(pageSize) / static_cast<std::uint32_t>(sizeof(PackedTriangle));
}

/** v2: node slots per Nodes page (48-byte records; the page's representations share its
 *  payload from the end, so a page may use fewer). Node index n is slot n mod this of the
 *  NodePages section's entry n / this. */
constexpr std::uint32_t nodesPerPageV2(std::uint32_t pageSize) noexcept {
    return pagePayloadBytes(pageSize) / 48u;
}

constexpr bool isValidPageSize(std::uint32_t pageSize) noexcept {
    return pageSize >= kMinPageSize && pageSize <= kMaxPageSize &&
           (pageSize & (pageSize - 1)) == 0;
}

} // namespace ff::storage
