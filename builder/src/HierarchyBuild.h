#pragma once

#include "OctreeBuilder.h"

#include <ff/builder/HierarchyParams.h>
#include <ff/builder/SceneSink.h>

#include <vector>

namespace ff::builder {

/**
 * Builds the hierarchy `params.decomposition` asks for over `triangles`, with the contract of
 * buildOctree: triangles reordered so that each node's own triangles are one run, in depth-first
 * order; nodes[0] the root, at `level`/`octant`, whose cell is `cell`; cubes baked. The
 * bounding-volume decompositions bake every cube directly over its node's bounding box; their
 * children may overlap, and a D-BVD geometry node holds the triangles pulled up at its level.
 * ORSD needs `grid`, and `cell` must be a block of it.
 */
std::vector<BuildNode> buildHierarchy(
        std::vector<storage::PackedTriangle>& triangles,
        const Cell& cell,
        int level,
        int octant,
        const HierarchyParams& params,
        CubeBaker& baker,
        const VoxelGrid* grid);

} // namespace ff::builder
