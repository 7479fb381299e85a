#pragma once

#include "OctreeBuilder.h"
#include "StandIns.h"

#include <ff/storage/SceneFormat.h>
#include <ff/storage/SceneWriter.h>
#include <ff/storage/Status.h>

#include <cstdint>
#include <optional>
#include <vector>

namespace ff::builder {

/**
 * A subtree ready to be written: geometry pages first, then node pages. Page numbers inside
 * (NodeRecord::firstChild.page, geometryPage of Cell nodes, rootRef) are relative to the
 * subtree's first page until commitSubtree() relocates them; those of nodes that came with
 * placedChildren or placedTriangles are final already.
 */
struct EncodedSubtree {
    std::vector<storage::PackedTriangle> triangles; ///< paged trianglesPerPage at a time
    struct Slot {
        storage::NodeRecord record;
        bool childrenPlacedElsewhere = false;  ///< firstChild is final: never relocated
        bool trianglesPlacedElsewhere = false; ///< geometryPage is final: never relocated
    };
    std::vector<std::vector<Slot>> nodePages;
    storage::NodeRef rootRef{0, 0}; ///< where the root sits
    std::uint64_t nodeCount = 0;    ///< records in nodePages
    std::uint32_t maxLevel = 0;     ///< deepest level

    std::uint64_t geometryPageCount(std::uint32_t pageSize) const;
};

/**
 * Lays `nodes` (nodes[0] = root, children contiguous) out in pages: whole sibling blocks in
 * breadth-first order of the subtree (level by level, octant order within a level), so the
 * pages a cut needs are the levels above it, the root first. The nodes' triangles are
 * reordered into the same breadth-first order, for the same reason. Nodes with placedChildren
 * or placedTriangles keep those (the tree above a prototype's chunks). Takes ownership of the
 * triangles.
 */
EncodedSubtree encodeSubtree(
        std::vector<BuildNode> nodes,
        std::vector<storage::PackedTriangle> triangles,
        std::uint32_t pageSize);

/**
 * A chunk, level by level and not yet placed, for a layout that puts each level of many chunks
 * together (LevelRegions). Its root is kept back for the tree above the chunks. References are
 * local until LevelRegions places the chunk: a record's firstChild is {0, index of the first
 * child in the next level's records}, a Cell record's geometry is {geometryPage 0,
 * geometryFirst = where its run starts in its level's triangles}; the root's placedChildren and
 * placedTriangles follow the same rule.
 */
struct LevelledSubtree {
    struct Level {
        std::vector<storage::NodeRecord> records; ///< the level's sibling blocks, in order
        std::vector<std::uint8_t> blocks;         ///< their sizes, in order
        std::uint64_t triangleBegin = 0;          ///< the level's range of `triangles`
        std::uint64_t triangleCount = 0;
        /** Format 2: per record, its stand-in (StandIns.h); empty when none or not asked. */
        std::vector<std::optional<StandIn>> standIns;
    };
    std::uint32_t rootLevel = 0;                    ///< octree level of levels[0]
    std::vector<Level> levels;                      ///< levels[d]: level rootLevel + d (levels[0]: no records)
    std::vector<storage::PackedTriangle> triangles; ///< breadth-first, so level by level
    /** The root: its children (placedChildren) and its triangles (placedTriangles) are in the
     *  levels, its record is written with the tree above the chunks. */
    BuildNode root;
    std::optional<StandIn> rootStandIn; ///< format 2: the root's, if it has one
    /** Format 2: what the root's subtree gives a stand-in above it. */
    StandInSource rootSource = StandInSource::unusable();
    std::uint64_t nodeCount = 0; ///< records in levels (the root not included)
    std::uint32_t maxLevel = 0;  ///< deepest level
};

/**
 * Splits a chunk into its root and the records below it, level by level, each level's records
 * and triangles in breadth-first order (encodeSubtree()'s order). The chunk must be below 2^32
 * triangles. Takes ownership of the triangles.
 */
LevelledSubtree encodeLevels(
        std::vector<BuildNode> nodes,
        std::vector<storage::PackedTriangle> triangles,
        std::vector<std::optional<StandIn>> standIns = {});

/** Writes the subtree's pages and makes its page numbers final. */
[[nodiscard]] Status commitSubtree(storage::SceneWriter& writer, EncodedSubtree& subtree);

} // namespace ff::builder
