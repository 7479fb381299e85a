// A format 2 node's cell, as a reader derives it from its parent's (NodeCellV2.h): octants
// tile their parent exactly, the builder's cells are found to float rounding down an octree's
// depth, a root's cube is octant 0 of its hierarchy's parent cell, and nothing else matches.

#include <ff/storage/NodeCellV2.h>

#include <gtest/gtest.h>

#include <cmath>

namespace ff::storage {
namespace {

// Siblings share faces exactly and together fill the parent: no gap or overlap between the
// cubes a reader draws.
TEST(NodeCellV2Test, OctantsTileTheirParentExactly) {
    const NodeBox cell{{-3.0f, 0.1f, 1e6f}, {5.0f, 8.1f, 1e6f + 8.0f}};
    for (std::uint8_t o = 0; o < 8; ++o) {
        const NodeBox c = octantCell(cell, o);
        for (std::size_t a = 0; a < 3; ++a) {
            const bool upper = (static_cast<unsigned>(o) >> a & 1u) != 0;
            EXPECT_EQ(upper ? c.max[a] : c.min[a], upper ? cell.max[a] : cell.min[a]);
            const NodeBox sibling = octantCell(cell, static_cast<std::uint8_t>(o ^ (1u << a)));
            EXPECT_EQ(upper ? c.min[a] : c.max[a], upper ? sibling.max[a] : sibling.min[a]);
        }
    }
}

// The builder halves a cube as min + half, size half (OctreeBuilder's Cell); down a random path
// (up to 20 levels, until a cell is 128 floats wide: below that the builder's own cells are no
// longer cubes), a reader's midpoints still find each cell, near the origin and far from it.
TEST(NodeCellV2Test, TheBuildersCellsAreFoundDownAnOctreesDepth) {
    for (const float origin : {0.0f, -250.0f, 4096.0f}) {
        float min[3] = {origin, origin + 1.0f, origin - 7.0f};
        float size = 37.5f;
        NodeBox parent{{min[0], min[1], min[2]}, {min[0] + size, min[1] + size, min[2] + size}};
        unsigned path = 0x9e3779b9u;
        const float ulp = std::nextafter(std::abs(origin) + 64.0f, INFINITY) - (std::abs(origin) + 64.0f);
        for (int level = 0; level < 20 && size > 128.0f * ulp; ++level, path = path * 1664525u + 1013904223u) {
            const auto octant = static_cast<std::uint8_t>(path >> 29);
            const float half = 0.5f * size;
            for (std::size_t a = 0; a < 3; ++a)
                min[a] += (static_cast<unsigned>(octant) >> a & 1u) != 0 ? half : 0.0f;
            size = half;
            const NodeBox cell{{min[0], min[1], min[2]}, {min[0] + size, min[1] + size, min[2] + size}};
            const std::optional<std::uint8_t> found = matchingOctant(cell, parent);
            ASSERT_TRUE(found.has_value()) << "origin " << origin << ", level " << level;
            EXPECT_EQ(*found, octant) << "origin " << origin << ", level " << level;
            parent = octantCell(parent, *found); // what the reader holds for the next level
        }
    }
}

TEST(NodeCellV2Test, ARootsCubeIsOctantZeroOfItsHierarchysParentCell) {
    const NodeBox hierarchy{{-10.0f, 2.0f, 3.0f}, {30.0f, 4.0f, 13.0f}};
    const float edge = rootCellEdge({40.0f, 2.0f, 10.0f});
    EXPECT_GT(edge, 40.0f);
    EXPECT_LT(edge, 40.001f);
    const NodeBox root{hierarchy.min, {-10.0f + edge, 2.0f + edge, 3.0f + edge}};
    const std::optional<std::uint8_t> found = matchingOctant(root, rootParentCell(hierarchy));
    ASSERT_TRUE(found.has_value());
    EXPECT_EQ(*found, 0);
}

// Bounds of a BVH node, a cell shifted by 1 % of its side, a degenerate parent: no octant, so
// the reader takes the bounds.
TEST(NodeCellV2Test, WhatIsNoOctantIsNotMatched) {
    const NodeBox parent{{0, 0, 0}, {8, 8, 8}};
    EXPECT_FALSE(matchingOctant({{0, 0, 0}, {3, 4, 4}}, parent).has_value());
    EXPECT_FALSE(matchingOctant({{0.04f, 0, 0}, {4.04f, 4, 4}}, parent).has_value());
    EXPECT_FALSE(matchingOctant({{0, 0, 0}, {8, 8, 8}}, parent).has_value());
    EXPECT_FALSE(matchingOctant({{0, 0, 0}, {0, 4, 4}}, {{0, 0, 0}, {0, 8, 8}}).has_value());
    NodeV2 node;
    node.bounds = {{1, 2, 3}, {4, 5, 6}};
    EXPECT_EQ(cellOfNode(node, parent), node.bounds);
    node.flags = kNodeV2OctantCell;
    node.octant = 6;
    EXPECT_EQ(cellOfNode(node, parent), (NodeBox{{0, 4, 4}, {4, 8, 8}}));
}

} // namespace
} // namespace ff::storage
