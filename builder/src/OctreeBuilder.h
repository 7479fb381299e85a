#pragma once

#include <ff/builder/ColorCube.h>
#include <ff/builder/HierarchyParams.h>
#include <ff/storage/SceneFormat.h>

#include <glm/glm.hpp>

#include <cstdint>
#include <optional>
#include <vector>

namespace ff::builder {

/** Where a triangle run starts: a Geometry page and a slot in it (storage/FORMAT.md §6). */
struct TriangleSlot {
    std::uint32_t page = 0;
    std::uint32_t slot = 0;
};

/** A node while the builder holds it in memory. Children of a node are contiguous. */
struct BuildNode {
    glm::vec3 cellMin{0.0f};
    glm::vec3 cellMax{0.0f};
    glm::vec3 boundsMin{0.0f};
    glm::vec3 boundsMax{0.0f};
    ColorCube cube;
    std::uint32_t firstChild = 0;
    std::uint32_t childCount = 0;
    std::uint8_t level = 0;
    std::uint8_t octant = 0;
    std::uint8_t kind = 0; ///< storage::NodeKind
    bool octreeChildren = false;
    std::uint64_t firstTriangle = 0; ///< own triangles: [firstTriangle, +triangleCount)
    std::uint64_t triangleCount = 0;
    std::uint32_t instanceIndex = 0; ///< kind == Instance
    /** Set when the node's children are placed elsewhere (a chunk's root): the ref of the
     *  first child, a page of the scene file once the chunks' level regions are written
     *  (LevelRegions); `firstChild` is unused. */
    std::optional<storage::NodeRef> placedChildren;
    /** Set when the node's own triangles are placed elsewhere (a chunk's root): where their
     *  run starts, final once the level regions are written; `firstTriangle` is unused. */
    std::optional<TriangleSlot> placedTriangles;
};

/** An octree cell: a cube. */
struct Cell {
    glm::vec3 min{0.0f};
    float size = 1.0f;
    glm::vec3 max() const { return min + glm::vec3(size); }
    Cell octantCell(int octant) const;
};

/** Octant of `point` in `cell` (bit0 x, bit1 y, bit2 z). */
int octantOf(const Cell& cell, const glm::vec3& point);

glm::vec3 centroid(const storage::PackedTriangle& t);
/** Longest edge of the triangle's bounding box. */
float extent(const storage::PackedTriangle& t);
void growBounds(glm::vec3& lo, glm::vec3& hi, const storage::PackedTriangle& t);

/**
 * Builds the octree over `triangles` (reordered in place so each node's own triangles are one
 * run, in depth-first order) inside `cell` at `level`, with cubes baked bottom-up. nodes[0] is
 * the root. Deterministic.
 */
std::vector<BuildNode> buildOctree(
        std::vector<storage::PackedTriangle>& triangles,
        const Cell& cell,
        int level,
        int octant,
        const HierarchyParams& params,
        CubeBaker& baker);

} // namespace ff::builder
