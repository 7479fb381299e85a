#pragma once

// The decompositions of Meißner, Bartz et al. (1999, §3) other than the octree, written once
// over boxes so that prototypes (items = triangles) and the instance level (items = instances)
// share them. The octree itself stays in OctreeBuilder: its cost rule and cube compositing
// need the triangles.

#include <ff/builder/HierarchyParams.h>
#include <ff/builder/SceneSink.h>

#include <glm/glm.hpp>

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

namespace ff::builder {

/** What a decomposition splits: an item's bounding box and its barycentre. */
struct SplitItem {
    glm::vec3 lo{0.0f};
    glm::vec3 hi{0.0f};
    glm::vec3 centre{0.0f};
};

/**
 * A node of a decomposed hierarchy. Its items are order[begin, end): its own items
 * [begin, ownEnd) first (a leaf owns all of them), then its children's, child by child, so
 * every subtree is one range and every item is in exactly one node.
 */
struct SplitNode {
    glm::vec3 boundsMin{0.0f}; ///< tight bounds of the subtree's items
    glm::vec3 boundsMax{0.0f};
    glm::vec3 cellMin{0.0f}; ///< the box its cube is baked over: the bounds, flat sides given
                             ///< a sliver of thickness (ORSD: the block)
    glm::vec3 cellMax{0.0f};
    std::uint64_t begin = 0;
    std::uint64_t ownEnd = 0;
    std::uint64_t end = 0;
    std::uint32_t firstChild = 0; ///< children are contiguous in the node array
    std::uint32_t childCount = 0;
    int level = 0;               ///< below the decomposition's root
    int octant = 0;              ///< ORSD: the octant of its parent block
    bool octreeChildren = false; ///< ORSD: the children are octant blocks, in octant order
};

/** Where ORSD starts: a block of the grid, `size` cells (a power of two) from cell `first`. */
struct GridBlock {
    glm::uvec3 first{0u};
    std::uint32_t size = 1;
};

/** The block of `grid` whose world box is the cube [min, min + edge]; nullopt if the cube is
 *  not a power-of-two block aligned to the grid. */
std::optional<GridBlock> gridBlockOf(const VoxelGrid& grid, const glm::vec3& min, float edge);

/** The smallest power-of-two block at the grid's first cell that covers the whole grid. */
GridBlock rootGridBlock(const VoxelGrid& grid);

/**
 * Decomposes `items` with `decomposition` (not Octree). `order` is filled with the item
 * indices in the layout SplitNode describes. nodes[0] is the root. Deterministic.
 * ORSD needs `grid` and the block it starts from; the others ignore them.
 */
std::vector<SplitNode> decompose(
        std::span<const SplitItem> items,
        std::vector<std::uint32_t>& order,
        Decomposition decomposition,
        const DecompositionParams& params,
        const VoxelGrid* grid = nullptr,
        GridBlock block = {});

} // namespace ff::builder
