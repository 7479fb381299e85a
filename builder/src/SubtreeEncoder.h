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
 * (NodeRecord::firstChild.page, geometryPage of Cell nodes) are relative to the subtree's first
 * page until commitSubtree() relocates them.
 */
struct EncodedSubtree {
    std::vector<storage::PackedTriangle> triangles; ///< paged trianglesPerPage at a time
    struct Slot {
        storage::NodeRecord record;
        bool absolute = false; ///< built elsewhere with final page numbers: never relocated
    };
    std::vector<std::vector<Slot>> nodePages;
    storage::NodeRecord root{};  ///< the root's record (also inside nodePages if placed)
    std::optional<storage::NodeRef> rootRef; ///< where the root sits, if it was placed
    std::uint64_t nodeCount = 0; ///< records in nodePages
    std::uint32_t maxLevel = 0;

    std::uint64_t geometryPageCount(std::uint32_t pageSize) const;
};

/**
 * Lays `nodes` (nodes[0] = root, children contiguous) out in pages: whole sibling blocks in
 * breadth-first order of the subtree (level by level, octant order within a level), so the
 * pages a cut needs are the levels above it. The nodes' triangles are reordered into the same
 * breadth-first order, for the same reason. With `placeRoot` false the root is left out (its
 * parent, built later, holds it). Takes ownership of the triangles.
 */
EncodedSubtree encodeSubtree(
        std::vector<BuildNode> nodes,
        std::vector<storage::PackedTriangle> triangles,
        std::uint32_t pageSize,
        bool placeRoot);

/** Writes the subtree's pages and returns its root record with final page numbers. */
[[nodiscard]] Result<storage::NodeRecord> commitSubtree(storage::SceneWriter& writer, EncodedSubtree& subtree);

/** Shifts the relative page numbers of `record` by the given bases. */
void relocateRecord(storage::NodeRecord& record, std::uint64_t geometryBase, std::uint64_t nodeBase);

} // namespace ff::builder
