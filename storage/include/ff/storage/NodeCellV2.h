#pragma once

// A format v2 node's cell: the box its colour cube was baked over and the ε rule measures
// (Chamberlain et al.'s cell). Octree nodes store which octant of their parent's cell they are
// (kNodeV2OctantCell), so the runtime measures and draws the builder's cells, not the bounds,
// which reach past an octree cell by up to a triangle on every side (FORMAT.md §5.3).

#include <ff/storage/NodeRecordV2.h>

#include <array>
#include <cstdint>
#include <optional>

namespace ff::storage {

/** A v2 node's decoded bounds and cell: what its children's records are read against (what a
 *  root's is read against: rootParentV2). */
struct DecodedNodeV2 {
    NodeBox bounds;
    NodeBox cell;
};

/** Octant `octant` (bit 0 x, bit 1 y, bit 2 z: the upper half) of `cell`. Siblings share
 *  their faces exactly: each axis splits at one midpoint. */
[[nodiscard]] NodeBox octantCell(const NodeBox& cell, std::uint8_t octant) noexcept;

/** The cell a hierarchy's root is read against (a root is octant 0 of it): the cube at the
 *  hierarchy box's min with twice the edge of the builder's root cube, whose edge is the box's
 *  largest side · (1 + 10⁻⁵) + the smallest normal float (rootCellEdge). */
[[nodiscard]] NodeBox rootParentCell(const NodeBox& hierarchy) noexcept;

/** What the root of a hierarchy whose box is `hierarchy` is read against. */
[[nodiscard]] DecodedNodeV2 rootParentV2(const NodeBox& hierarchy) noexcept;

/** Edge of the octree's root cube around a box of `size`: a hair larger than its largest
 *  side, so that no centroid sits on the cube's max face. */
[[nodiscard]] float rootCellEdge(const std::array<float, 3>& size) noexcept;

/** The cell of a node read against a parent whose cell is `parentCell`: octant `octant` of it
 *  with kNodeV2OctantCell, else the node's decoded bounds. */
[[nodiscard]] NodeBox cellOfNode(const NodeV2& node, const NodeBox& parentCell) noexcept;

/**
 * The octant of `parentCell` that is `cell`, to float rounding (every face within 10⁻³ of the
 * octant's side or a few units in the last place of the coordinates): what a writer flags with
 * kNodeV2OctantCell. Empty where no octant is: the node's cell is then read as its bounds.
 */
[[nodiscard]] std::optional<std::uint8_t>
matchingOctant(const NodeBox& cell, const NodeBox& parentCell) noexcept;

} // namespace ff::storage
