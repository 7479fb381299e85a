#pragma once

// Format 2's leaves are whole clusters: a subtree small enough becomes one leaf that owns all
// its triangles, so a 48-byte record stands for thousands of triangles, not ten.

#include "OctreeBuilder.h"

#include <ff/storage/SceneFormat.h>

#include <cstdint>
#include <span>
#include <vector>

namespace ff::builder {

/**
 * Makes every Cell subtree of at most `leafTriangles` triangles (whose root has children) one
 * leaf owning the subtree's triangles, outermost first. Reorders `triangles` depth first (a
 * node's own run, then its children's subtrees in order), which makes each collapsed subtree's
 * triangles one run; every reachable node's [firstTriangle, +triangleCount) is its run
 * afterwards. The nodes below a collapsed one stay in `nodes`, unreachable. A node with
 * placedChildren or placedTriangles (a chunk's root, whose payload lives elsewhere) is never
 * collapsed, nor is any node above it. Children must come after their parents in `nodes`.
 * Returns the nodes made leaves.
 */
std::uint64_t collapseSmallSubtrees(
        std::vector<BuildNode>& nodes,
        std::span<storage::PackedTriangle> triangles,
        std::uint64_t leafTriangles);

} // namespace ff::builder
