#pragma once

// Format 2's leaves are whole clusters (LeafCollapse.h), so a leaf of thousands of triangles
// would refine from its one cube straight to all of them. A child per cluster, with its own
// bounds and color cube, lets the cut stop inside the leaf: a piece is drawn where its box is
// larger than ε on screen, its cube where it is not. The pieces are cut in space (slabs of the
// leaf's centroids), not taken from the meshlet builder, whose meshlets can be scattered
// enough to leave their boxes' cubes half transparent; each encodes to one or two clusters.

#include "OctreeBuilder.h"

#include <ff/builder/ClusterBuild.h>
#include <ff/storage/ClusterCodec.h>
#include <ff/storage/SceneFormat.h>
#include <ff/storage/Status.h>

#include <cstdint>
#include <span>
#include <vector>

namespace ff::builder {

/** How leaves become cluster nodes. */
struct LeafShapeV2 {
    /** Subtrees of at most this many triangles become one leaf (0: keep the hierarchy's). */
    std::uint64_t leafTriangles = 0;
    /** Split every leaf into a child per cluster (false: a leaf draws all its clusters). */
    bool clusterNodes = false;
    const storage::PositionGrid* grid = nullptr; ///< the prototype's: clusters form on it
    ClusterLimits limits;                        ///< the encoder's
    int bakeResolution = 8;                      ///< of the clusters' cubes
    unsigned threads = 1;
};

/** A node has at most this many children (the record's child count is a byte). */
inline constexpr std::uint32_t kMaxClusterChildren = 255;

/**
 * Gives every reachable Cell leaf with triangles of its own (not placed elsewhere) whose
 * triangles form more than one cluster as many children as clusters (at most
 * kMaxClusterChildren), appended to `nodes`: spatially compact pieces of its triangles, each
 * with their bounds and cube, one level below the leaf, which keeps its cube and gives up its
 * triangles. Each split leaf's run of `triangles` is reordered piece by piece. Deterministic
 * whatever `shape.threads`. Returns the leaves split.
 */
[[nodiscard]] Result<std::uint64_t> splitLeavesIntoClusters(
        std::vector<BuildNode>& nodes,
        std::span<storage::PackedTriangle> triangles,
        const LeafShapeV2& shape);

/** Format 2's leaves: small subtrees collapsed into one leaf (collapseSmallSubtrees), then
 *  split into cluster nodes when `shape.clusterNodes`. */
[[nodiscard]] Status shapeLeavesV2(
        std::vector<BuildNode>& nodes,
        std::span<storage::PackedTriangle> triangles,
        const LeafShapeV2& shape);

} // namespace ff::builder
