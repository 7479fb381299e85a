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
 * (NodeRecord::firstChild.page, geometryPage of Cell nodes, the crown's placedChildren) are
 * relative to the subtree's first page until commitSubtree() relocates them.
 *
 * The crown is the subtree's top levels, held back for the tree above (a chunk's crown is laid
 * out with the cells above the chunks): crown[0] is the root, children are contiguous, a crown
 * node either has its children in the crown (firstChild) or already placed (placedChildren),
 * and firstTriangle indexes crownTriangles.
 */
struct EncodedSubtree {
    std::vector<storage::PackedTriangle> triangles; ///< paged trianglesPerPage at a time
    struct Slot {
        storage::NodeRecord record;
        bool childrenPlacedElsewhere = false; ///< firstChild is final: never relocated
    };
    std::vector<std::vector<Slot>> nodePages;
    std::optional<storage::NodeRef> rootRef; ///< where the root sits, if it was placed
    std::vector<BuildNode> crown;
    std::vector<storage::PackedTriangle> crownTriangles;
    std::uint64_t nodeCount = 0; ///< records in nodePages
    std::uint32_t maxLevel = 0;  ///< deepest level, crown included

    std::uint64_t geometryPageCount(std::uint32_t pageSize) const;
};

/**
 * Lays `nodes` (nodes[0] = root, children contiguous) out in pages: whole sibling blocks in
 * breadth-first order of the subtree (level by level, octant order within a level), so the
 * pages a cut needs are the levels above it. The nodes' triangles are reordered into the same
 * breadth-first order, for the same reason. With `crownBudget` 0 everything is placed, the
 * root first; otherwise the root and as many whole levels below it as fit in `crownBudget`
 * nodes form the crown and are not placed. Nodes with placedChildren keep those children.
 * Takes ownership of the triangles.
 */
EncodedSubtree encodeSubtree(
        std::vector<BuildNode> nodes,
        std::vector<storage::PackedTriangle> triangles,
        std::uint32_t pageSize,
        std::uint64_t crownBudget);

/** Writes the subtree's pages and makes its page numbers (the crown's too) final. */
[[nodiscard]] Status commitSubtree(storage::SceneWriter& writer, EncodedSubtree& subtree);

} // namespace ff::builder
