#pragma once

// Format 2's leaves are whole clusters (LeafCollapse.h), so a leaf of thousands of triangles
// would refine from its one cube straight to all of them. A node per cluster, with its own
// bounds and color cube, under a small tree of nodes over groups of them, lets the cut stop
// inside the leaf: a piece is drawn where its box is larger than ε on screen, its cube where it
// is not. The pieces are cut in space (slabs of the leaf's centroids), not taken from the
// meshlet builder, whose meshlets can be scattered enough to leave their boxes' cubes half
// transparent; each is sized to encode to one cluster (kPiecesPerCluster).

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

/** The nodes below a split leaf have at most this many children. Four, as a terrain's octree
 *  has: with many more, a node just over ε on screen would refine into children far below it
 *  (a leaf of 23 clusters at 1.3 px into cubes of 0.3 px), and a far view would read and draw
 *  a record for every fraction of a pixel. */
inline constexpr std::uint32_t kClusterNodeBranching = 4;

/** A leaf is cut into this many times as many pieces as the clusters its whole run encodes to.
 *  A slab's edge runs through grid cells, so a piece of the meshlet builder's average size has
 *  a few more vertices than a cluster holds (128) and encodes to two clusters: measured on the
 *  4 M terrain from leaves of 65,536 triangles, 1.0 gives 1.94 clusters a piece (7.78 bytes a
 *  triangle), 1.1 one (7.34), 1.15 one (7.54), 1.3 1.0 again but smaller (7.78). */
inline constexpr double kPiecesPerCluster = 1.1;

/**
 * Gives every reachable Cell leaf with triangles of its own (not placed elsewhere) whose
 * triangles form more than one cluster a tree of nodes below it, at most
 * kClusterNodeBranching children wide, appended to `nodes`: its leaves are spatially compact
 * pieces of the triangles, each sized to encode to one cluster (kPiecesPerCluster), and every
 * node has its bounds and a cube baked on them; the split leaf keeps its cube and gives up its
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
