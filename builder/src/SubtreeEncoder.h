#pragma once

#include "OctreeBuilder.h"

#include <ff/storage/SceneFormat.h>
#include <ff/storage/SceneWriter.h>
#include <ff/storage/Status.h>

#include <cstdint>
#include <optional>
#include <vector>

namespace ff::builder {

/**
 * A subtree ready to be written: geometry pages first, then node pages. Page numbers inside
 * (NodeRecord::firstChild.page, geometryPage of Cell nodes, the crown's placedChildren and
 * placedTriangles) are relative to the subtree's first page until commitSubtree() relocates
 * them.
 *
 * The crown is the subtree's top levels, held back for the tree above (a chunk's crown is laid
 * out with the cells above the chunks): crown[0] is the root, children are contiguous, a crown
 * node either has its children in the crown (firstChild) or already placed (placedChildren),
 * and its triangles either in crownTriangles (firstTriangle) or, past the crown's triangle
 * budget, in the subtree's own geometry (placedTriangles).
 */
struct EncodedSubtree {
    std::vector<storage::PackedTriangle> triangles; ///< paged trianglesPerPage at a time
    struct Slot {
        storage::NodeRecord record;
        bool childrenPlacedElsewhere = false;  ///< firstChild is final: never relocated
        bool trianglesPlacedElsewhere = false; ///< geometryPage is final: never relocated
    };
    std::vector<std::vector<Slot>> nodePages;
    std::optional<storage::NodeRef> rootRef; ///< where the root sits, if it was placed
    std::vector<BuildNode> crown;
    std::vector<storage::PackedTriangle> crownTriangles;
    std::uint64_t nodeCount = 0; ///< records in nodePages
    std::uint32_t maxLevel = 0;  ///< deepest level, crown included

    std::uint64_t geometryPageCount(std::uint32_t pageSize) const;
};

/** How much of a subtree may be held back as its crown; 0 nodes: no crown. */
struct CrownBudget {
    std::uint64_t nodes = 0;
    std::uint64_t triangles = 0;
};

/**
 * Lays `nodes` (nodes[0] = root, children contiguous) out in pages: whole sibling blocks in
 * breadth-first order of the subtree (level by level, octant order within a level), so the
 * pages a cut needs are the levels above it. The nodes' triangles are reordered into the same
 * breadth-first order, for the same reason. With a crown budget of 0 nodes everything is
 * placed, the root first; otherwise the root and as many whole levels below it as fit the
 * budget's nodes form the crown and are not placed, and the crown's triangles, in
 * breadth-first order, move with it while they fit the budget's triangles. Nodes with
 * placedChildren or placedTriangles keep those. Takes ownership of the triangles.
 */
EncodedSubtree encodeSubtree(
        std::vector<BuildNode> nodes,
        std::vector<storage::PackedTriangle> triangles,
        std::uint32_t pageSize,
        CrownBudget crownBudget);

/** Writes the subtree's pages and makes its page numbers (the crown's too) final. */
[[nodiscard]] Status commitSubtree(storage::SceneWriter& writer, EncodedSubtree& subtree);

} // namespace ff::builder
