#include "HierarchyBuild.h"

#include "Decomposition.h"

#include <ff/storage/Assert.h>

#include <algorithm>
#include <limits>

namespace ff::builder {

namespace {

/** triangles[i] = old triangles[order[i]], in place, following the permutation's cycles. */
void applyOrder(
        std::vector<storage::PackedTriangle>& triangles, const std::vector<std::uint32_t>& order) {
    std::vector<bool> placed(triangles.size(), false);
    for (std::size_t start = 0; start < triangles.size(); ++start) {
        if (placed[start])
            continue;
        const storage::PackedTriangle first = triangles[start];
        std::size_t at = start;
        while (order[at] != start) {
            triangles[at] = triangles[order[at]];
            placed[at] = true;
            at = order[at];
        }
        triangles[at] = first;
        placed[at] = true;
    }
}

} // namespace

std::vector<BuildNode> buildHierarchy(
        std::vector<storage::PackedTriangle>& triangles,
        const Cell& cell,
        int level,
        int octant,
        const HierarchyParams& params,
        CubeBaker& baker,
        const VoxelGrid* grid) {
    if (params.decomposition == Decomposition::Octree)
        return buildOctree(triangles, cell, level, octant, params, baker);

    std::vector<SplitItem> items(triangles.size());
    for (std::size_t i = 0; i < triangles.size(); ++i) {
        SplitItem& item = items[i];
        item.lo = glm::vec3(std::numeric_limits<float>::infinity());
        item.hi = glm::vec3(-std::numeric_limits<float>::infinity());
        growBounds(item.lo, item.hi, triangles[i]);
        item.centre = centroid(triangles[i]);
    }
    GridBlock block;
    if (params.decomposition == Decomposition::Orsd) {
        FF_ASSERT(grid != nullptr); // ORSD needs a voxel grid
        const std::optional<GridBlock> start = gridBlockOf(*grid, cell.min, cell.size);
        FF_ASSERT(start.has_value()); // an ORSD cell is a block of its grid
        block = *start;
    }
    std::vector<std::uint32_t> order;
    const std::vector<SplitNode> split =
            decompose(items, order, params.decomposition, params.split, grid, block);
    items = {};
    applyOrder(triangles, order);

    std::vector<BuildNode> nodes(split.size());
    for (std::size_t n = 0; n < split.size(); ++n) {
        const SplitNode& s = split[n];
        BuildNode& node = nodes[n];
        node.cellMin = s.cellMin;
        node.cellMax = s.cellMax;
        node.boundsMin = s.boundsMin;
        node.boundsMax = s.boundsMax;
        node.firstChild = s.firstChild;
        node.childCount = s.childCount;
        node.level = static_cast<std::uint8_t>(level + s.level);
        node.octant = static_cast<std::uint8_t>(s.octant);
        node.kind = static_cast<std::uint8_t>(storage::NodeKind::Cell);
        node.octreeChildren = s.octreeChildren;
        node.firstTriangle = s.begin;
        node.triangleCount = s.ownEnd - s.begin;
    }
    // The root is the cell it was asked for: the tree above (a prototype's top cells, or the
    // instance level) knows it by that cell.
    nodes[0].cellMin = cell.min;
    nodes[0].cellMax = cell.max();
    nodes[0].level = static_cast<std::uint8_t>(level);
    nodes[0].octant = static_cast<std::uint8_t>(octant);
    // Bottom-up (children come after their parent): a leaf from its triangles; an inner node
    // from its own triangles over its children's boxes, each seen through its cube (as the
    // instance level bakes), or with --bake-inner direct from every triangle below it, which
    // costs a pass over the triangles per level.
    const glm::mat4 identity(1.0f);
    for (std::size_t n = split.size(); n-- > 0;) {
        const SplitNode& s = split[n];
        BuildNode& node = nodes[n];
        baker.reset(node.cellMin, node.cellMax);
        const bool direct = s.childCount == 0 || params.bakeInnerDirect;
        const std::uint64_t end = direct ? s.end : s.ownEnd;
        baker.addTriangles(std::span(triangles).subspan(s.begin, end - s.begin));
        if (!direct)
            for (std::uint32_t c = 0; c < s.childCount; ++c) {
                const BuildNode& child = nodes[s.firstChild + c];
                baker.addBox(identity, child.cellMin, child.cellMax, child.cube);
            }
        node.cube = baker.finish();
    }
    return nodes;
}

} // namespace ff::builder
