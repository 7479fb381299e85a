#pragma once

// Format v2's node record: 48 bytes with the 24-byte color cube inline (so a resident node can
// always be drawn), bounds quantized outward relative to the parent's, children addressed by
// one node index, and a representation table that names any number of payloads of any kind.
// storage/FORMAT.md §5.3 documents every byte; `build --format 2` writes it (NodePageV2.h).
//
// Free functions over bytes: decoding checks every field; the bounds decode relative to the
// parent's decoded bounds, which a top-down walk always holds.

#include <ff/storage/Status.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

namespace ff::storage {

inline constexpr std::size_t kNodeRecordV2Size = 48;
inline constexpr std::size_t kRepresentationRecordSize = 20;

/** Steps of the bounds' quantization per axis: 10 bits, in [0, 1023] of the parent's extent. */
inline constexpr std::uint32_t kNodeBoundsSteps = 1023;

/** An axis-aligned box in its hierarchy's frame. */
struct NodeBox {
    std::array<float, 3> min{0.0f, 0.0f, 0.0f};
    std::array<float, 3> max{0.0f, 0.0f, 0.0f};

    friend bool operator==(const NodeBox&, const NodeBox&) = default;
};

enum class NodeKindV2 : std::uint8_t {
    Cell = 0,     ///< a node of a hierarchy: children and/or payloads
    Instance = 1, ///< an instance: `firstRepresentation` is its instance index
};

enum NodeFlagsV2 : std::uint8_t {
    kNodeV2HasCube = 1u << 0,        ///< `cube` holds a baked color cube
    kNodeV2OctreeChildren = 1u << 1, ///< children are octants of this node's box
    kNodeV2Unlit = 1u << 2,          ///< drawn with its colours as they are (KHR_materials_unlit)
    /** Its cell (the box its cube was baked over and the ε rule measures) is octant `octant` of
     *  its parent's cell (cellOfNode); without it the cell is its bounds. */
    kNodeV2OctantCell = 1u << 3,
};
inline constexpr std::uint8_t kKnownNodeV2Flags =
        kNodeV2HasCube | kNodeV2OctreeChildren | kNodeV2Unlit | kNodeV2OctantCell;

/** A node as the runtime sees it, its bounds decoded. */
struct NodeV2 {
    NodeBox bounds; ///< conservative: contains everything below
    std::array<std::array<std::uint8_t, 4>, 6>
            cube{};               ///< premultiplied linear RGBA8, kCubeFace order
    std::uint32_t firstChild = 0; ///< node index of the first child (children consecutive)
    /** Triangles drawn below (instances counted as drawn), for statistics such as the triangles
     *  occlusion culling saved: exact up to 2^24, a float beyond. */
    float subtreeTriangles = 0.0f;
    std::uint32_t firstRepresentation =
            0; ///< Cell: index in the representation table; Instance: the instance
    std::uint8_t childCount = 0;
    std::uint8_t representationCount = 0;
    NodeKindV2 kind = NodeKindV2::Cell;
    std::uint8_t flags = 0;  ///< NodeFlagsV2
    std::uint8_t octant = 0; ///< with kNodeV2OctantCell: bit 0 x, bit 1 y, bit 2 z high; else 0
};

/** What a payload holds. New kinds are added here, not by a new format. */
enum class RepresentationKind : std::uint8_t {
    Clusters = 1,        ///< ClusterCodec clusters, back to back
    /** Point splats standing in for the node's subtree (always flagged kRepresentationStandIn):
     *  a run of clusters as Clusters, point clusters (no triangles) and clusters of the
     *  triangles too large to splat; `parameter` is its error (FORMAT.md §5.3). */
    Splats = 2,
    KeyframedSplats = 3, ///< reserved for animated splats
    ImageLevel = 4,      ///< reserved for image-based levels
    VisibleSet = 5,      ///< reserved for precomputed visibility
};

enum RepresentationFlags : std::uint8_t {
    /** A stand-in for the node's whole subtree (its own payloads and everything below it),
     *  drawn instead of them where its error is small enough on screen: Clusters (simplified)
     *  or Splats; `parameter` is its error in the hierarchy's units (FORMAT.md §5.3). */
    kRepresentationStandIn = 1u << 0,
};
inline constexpr std::uint8_t kKnownRepresentationFlags = kRepresentationStandIn;

/** One payload of a node: `length` bytes at byte `offset` of payload page `page`. */
struct RepresentationRecord {
    RepresentationKind kind = RepresentationKind::Clusters;
    std::uint8_t flags = 0;
    std::uint16_t count = 0; ///< items in the payload (clusters, splat blocks, ...)
    std::uint32_t page = 0;
    std::uint32_t offset = 0;
    std::uint32_t length = 0;
    /** The kind's own parameter: a stand-in's error (its hierarchy's units, >= 0), a splat
     *  spacing, ...; 0 where the kind has none. */
    float parameter = 0.0f;

    friend bool operator==(const RepresentationRecord&, const RepresentationRecord&) = default;
};

/**
 * The smallest box of the quantized ones around `box` inside `parent`: what decodeNodeV2 gives
 * back for a node with these bounds. `box` must lie inside `parent` (InvalidArgument if not).
 */
[[nodiscard]] Result<NodeBox> quantizeBoundsOutward(const NodeBox& box, const NodeBox& parent);

/** Writes `node` into `out`; its bounds are stored outward relative to `parent` (the parent's
 *  decoded bounds, or the hierarchy's root box for a root). */
[[nodiscard]] Status
encodeNodeV2(const NodeV2& node, const NodeBox& parent, std::span<std::byte> out);

/** Reads and checks the record at the start of `bytes` (at least kNodeRecordV2Size). */
[[nodiscard]] Result<NodeV2> decodeNodeV2(std::span<const std::byte> bytes, const NodeBox& parent);

[[nodiscard]] Status encodeRepresentation(const RepresentationRecord& r, std::span<std::byte> out);
/** Reads and checks the record at the start of `bytes`: a known kind, known flags (a stand-in
 *  only of clusters or splats, its error >= 0; splats only as a stand-in), a finite parameter; where it points is checked by who
 *  reads the page. */
[[nodiscard]] Result<RepresentationRecord> decodeRepresentation(std::span<const std::byte> bytes);

/** Whether `r` is a subtree's stand-in (kRepresentationStandIn: simplified clusters or
 *  splats), not the node's own payload. */
constexpr bool isStandIn(const RepresentationRecord& r) noexcept {
    return (r.flags & kRepresentationStandIn) != 0;
}

} // namespace ff::storage
