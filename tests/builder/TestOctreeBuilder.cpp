// The in-memory octree (builder/src/OctreeBuilder.h): Chamberlain et al.'s cost rule, no nodes
// for empty space, each triangle in exactly one node's own run (depth-first order), large
// triangles kept at inner nodes, maxDepth, tight bounds and bottom-up cubes.

#include "BuiltScene.h"
#include "OctreeBuilder.h"

#include <ff/builder/ColorCube.h>
#include <ff/builder/HierarchyParams.h>
#include <ff/builder/SceneSink.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <vector>

namespace ff::builder {
namespace {

/** A small triangle in the z = const plane whose centroid is `center`; `tag` makes it unique. */
storage::PackedTriangle triangleAt(const glm::vec3& center, float size, int tag = 0) {
    const glm::vec3 n(0.0f, 0.0f, 1.0f);
    const glm::vec4 color(
            static_cast<float>(tag % 256) / 255.0f,
            static_cast<float>(tag / 256 % 256) / 255.0f,
            0.5f,
            1.0f);
    const float t = size / 3.0f;
    return packTriangle(
            {center + glm::vec3(-t, -t, 0.0f), n, color},
            {center + glm::vec3(2.0f * t, -t, 0.0f), n, color},
            {center + glm::vec3(-t, 2.0f * t, 0.0f), n, color});
}

/** Centres of octant `o` of the unit cell, jittered by `k` so triangles stay apart. */
glm::vec3 inOctant(int o, int k = 0) {
    const glm::vec3 base((o & 1) ? 0.75f : 0.25f, (o & 2) ? 0.75f : 0.25f, (o & 4) ? 0.75f : 0.25f);
    return base +
           glm::vec3(
                   0.01f * static_cast<float>(k % 7), 0.01f * static_cast<float>(k / 7 % 7), 0.0f);
}

using testing::Lcg;

std::vector<storage::PackedTriangle> randomTriangles(std::size_t count, std::uint64_t seed) {
    Lcg rng(seed);
    std::vector<storage::PackedTriangle> out;
    for (std::size_t i = 0; i < count; ++i) {
        const glm::vec3 c(rng.next(), rng.next(), rng.next());
        // Mostly tiny, some medium, a few large (up to 0.9 of the cell).
        const float r = rng.next();
        const float size = r < 0.9f ? 0.004f : (r < 0.99f ? 0.06f : 0.9f * rng.next());
        out.push_back(triangleAt(c * 0.9f + glm::vec3(0.05f), size, static_cast<int>(i)));
    }
    return out;
}

/** The triangles as sorted byte strings: equal for equal multisets. */
std::vector<std::string> asMultiset(std::span<const storage::PackedTriangle> triangles) {
    std::vector<std::string> out;
    out.reserve(triangles.size());
    for (const storage::PackedTriangle& t : triangles)
        out.emplace_back(reinterpret_cast<const char*>(&t), sizeof(t)); // byte view: may alias
    std::sort(out.begin(), out.end());
    return out;
}

struct Built {
    std::vector<BuildNode> nodes;
    std::vector<storage::PackedTriangle> triangles; ///< reordered
};

Built build(
        std::vector<storage::PackedTriangle> triangles,
        const HierarchyParams& params = {},
        const Cell& cell = {glm::vec3(0.0f), 1.0f},
        int level = 0,
        int octant = 0) {
    CubeBaker baker(params.bakeResolution);
    std::vector<BuildNode> nodes = buildOctree(triangles, cell, level, octant, params, baker);
    return {std::move(nodes), std::move(triangles)};
}

std::span<const storage::PackedTriangle> own(const Built& b, const BuildNode& node) {
    return std::span(b.triangles).subspan(node.firstTriangle, node.triangleCount);
}

/** Triangles of the node's subtree: its own run followed by its descendants', contiguous. */
std::uint64_t subtreeEnd(const Built& b, std::size_t index) {
    const BuildNode& node = b.nodes[index];
    if (node.childCount == 0)
        return node.firstTriangle + node.triangleCount;
    return subtreeEnd(b, node.firstChild + node.childCount - 1);
}

void collectPreorder(const Built& b, std::size_t index, std::vector<std::size_t>& out) {
    out.push_back(index);
    const BuildNode& node = b.nodes[index];
    for (std::uint32_t c = 0; c < node.childCount; ++c)
        collectPreorder(b, node.firstChild + c, out);
}

/** Every structural promise of buildOctree(), checked on any output. */
void expectOctreeInvariants(
        const Built& b,
        const std::vector<storage::PackedTriangle>& input,
        const HierarchyParams& params,
        int rootLevel = 0) {
    ASSERT_FALSE(b.nodes.empty());
    EXPECT_EQ(asMultiset(b.triangles), asMultiset(input)) << "triangles were lost or invented";

    // Own runs, visited depth-first, tile [0, N) in order: each triangle in exactly one node.
    std::vector<std::size_t> order;
    collectPreorder(b, 0, order);
    EXPECT_EQ(order.size(), b.nodes.size()) << "nodes unreachable from the root";
    std::uint64_t cursor = 0;
    for (std::size_t index : order) {
        EXPECT_EQ(b.nodes[index].firstTriangle, cursor) << "node " << index;
        cursor = b.nodes[index].firstTriangle + b.nodes[index].triangleCount;
    }
    EXPECT_EQ(cursor, b.triangles.size());

    for (std::size_t index = 0; index < b.nodes.size(); ++index) {
        SCOPED_TRACE(::testing::Message() << "node " << index);
        const BuildNode& node = b.nodes[index];
        const float size = node.cellMax.x - node.cellMin.x;
        const float limit = params.largeTriangleTolerance * size;
        const std::uint64_t end = subtreeEnd(b, index);
        EXPECT_GT(end, node.firstTriangle) << "a node for empty space";
        EXPECT_LE(static_cast<int>(node.level), params.maxDepth);
        EXPECT_GE(static_cast<int>(node.level), rootLevel);
        EXPECT_EQ(node.kind, static_cast<std::uint8_t>(storage::NodeKind::Cell));

        // Tight bounds: the union of the own triangles and the children's bounds.
        glm::vec3 lo(std::numeric_limits<float>::infinity());
        glm::vec3 hi(-std::numeric_limits<float>::infinity());
        for (const storage::PackedTriangle& t : own(b, node))
            growBounds(lo, hi, t);
        for (std::uint32_t c = 0; c < node.childCount; ++c) {
            lo = glm::min(lo, b.nodes[node.firstChild + c].boundsMin);
            hi = glm::max(hi, b.nodes[node.firstChild + c].boundsMax);
        }
        EXPECT_EQ(node.boundsMin, lo);
        EXPECT_EQ(node.boundsMax, hi);
        for (std::uint64_t i = node.firstTriangle; i < end; ++i) {
            glm::vec3 tlo(std::numeric_limits<float>::infinity());
            glm::vec3 thi(-std::numeric_limits<float>::infinity());
            growBounds(tlo, thi, b.triangles[i]);
            EXPECT_TRUE(
                    glm::all(glm::lessThanEqual(node.boundsMin, tlo)) &&
                    glm::all(glm::lessThanEqual(thi, node.boundsMax)));
        }

        // Cube faces are premultiplied alphas in [0, 1].
        for (const glm::vec4& face : node.cube.faces) {
            EXPECT_GE(face.a, 0.0f);
            EXPECT_LE(face.a, 1.0f + 1e-6f);
            for (int k = 0; k < 3; ++k)
                EXPECT_LE(face[k], face.a + 1e-6f);
        }

        // The small triangles of the subtree (those that may descend) and their octants.
        const Cell cell{node.cellMin, size};
        std::uint64_t small = 0;
        std::array<std::uint64_t, 8> perOctant{};
        for (std::uint64_t i = node.firstTriangle; i < end; ++i) {
            if (extent(b.triangles[i]) > limit)
                continue;
            ++small;
            ++perOctant[static_cast<std::size_t>(octantOf(cell, centroid(b.triangles[i])))];
        }
        const auto nonEmpty = static_cast<std::uint32_t>(std::count_if(
                perOctant.begin(), perOctant.end(), [](std::uint64_t n) { return n > 0; }));

        if (node.childCount == 0) {
            // A leaf: at maxDepth, or drawing its triangles is no dearer than the children's cubes.
            if (node.level < params.maxDepth) {
                EXPECT_LE(
                        static_cast<float>(small), params.cubeCost * static_cast<float>(nonEmpty));
            }
            continue;
        }
        // An inner node keeps exactly its large triangles; the rest descend into one child per
        // non-empty octant, in octant order, because they cost more than the children's cubes.
        EXPECT_TRUE(node.octreeChildren);
        EXPECT_LT(static_cast<int>(node.level), params.maxDepth);
        EXPECT_GT(static_cast<float>(small), params.cubeCost * static_cast<float>(nonEmpty));
        for (const storage::PackedTriangle& t : own(b, node))
            EXPECT_GT(extent(t), limit);
        EXPECT_EQ(node.childCount, nonEmpty);
        int previousOctant = -1;
        for (std::uint32_t c = 0; c < node.childCount; ++c) {
            const BuildNode& child = b.nodes[node.firstChild + c];
            EXPECT_GT(node.firstChild, index);
            EXPECT_GT(static_cast<int>(child.octant), previousOctant);
            previousOctant = child.octant;
            EXPECT_EQ(child.level, node.level + 1);
            const Cell expectedCell = cell.octantCell(child.octant);
            EXPECT_EQ(child.cellMin, expectedCell.min);
            EXPECT_EQ(child.cellMax, expectedCell.max());
            const std::uint64_t childEnd = subtreeEnd(b, node.firstChild + c);
            EXPECT_EQ(childEnd - child.firstTriangle, perOctant[child.octant]);
            for (std::uint64_t i = child.firstTriangle; i < childEnd; ++i)
                EXPECT_EQ(octantOf(cell, centroid(b.triangles[i])), child.octant);
        }
    }
}

std::vector<storage::PackedTriangle>
trianglesInOctants(const std::vector<std::pair<int, int>>& octantCounts) {
    std::vector<storage::PackedTriangle> out;
    int tag = 0;
    for (const auto& [octant, count] : octantCounts)
        for (int k = 0; k < count; ++k, ++tag)
            out.push_back(triangleAt(inOctant(octant, k), 0.005f, tag));
    return out;
}

// ---------------------------------------------------------------------------------------------

TEST(OctreeBuilderTest, CellWithAtMostCubeCostPerChildIsALeaf) {
    // 6 + 6 triangles in two octants: 12 <= 6 x 2, drawing them is no dearer than two cubes.
    const auto input = trianglesInOctants({{0, 6}, {7, 6}});
    const Built b = build(input);
    ASSERT_EQ(b.nodes.size(), 1u);
    EXPECT_EQ(b.nodes[0].childCount, 0u);
    EXPECT_EQ(b.nodes[0].triangleCount, 12u);
    expectOctreeInvariants(b, input, {});
}

TEST(OctreeBuilderTest, CellWithMoreThanCubeCostPerChildIsSubdivided) {
    // 7 + 6 in two octants: 13 > 12. The 7 lie in two sub-octants, so that child is a leaf.
    std::vector<storage::PackedTriangle> input = trianglesInOctants({{7, 6}});
    for (int k = 0; k < 4; ++k)
        input.push_back(triangleAt(
                glm::vec3(0.1f + 0.01f * static_cast<float>(k), 0.1f, 0.1f), 0.005f, 100 + k));
    for (int k = 0; k < 3; ++k)
        input.push_back(triangleAt(
                glm::vec3(0.4f, 0.4f - 0.01f * static_cast<float>(k), 0.4f), 0.005f, 200 + k));
    const Built b = build(input);
    ASSERT_EQ(b.nodes.size(), 3u);
    const BuildNode& root = b.nodes[0];
    EXPECT_EQ(root.childCount, 2u);
    EXPECT_EQ(root.triangleCount, 0u);
    EXPECT_EQ(b.nodes[root.firstChild].octant, 0);
    EXPECT_EQ(b.nodes[root.firstChild].triangleCount, 7u);
    EXPECT_EQ(b.nodes[root.firstChild + 1].octant, 7);
    EXPECT_EQ(b.nodes[root.firstChild + 1].triangleCount, 6u);
    expectOctreeInvariants(b, input, {});
}

TEST(OctreeBuilderTest, CubeCostIsAParameter) {
    // Two triangles in two sub-octants of octant 1, one in octant 6.
    const std::vector<storage::PackedTriangle> input = {
            triangleAt(glm::vec3(0.6f, 0.1f, 0.1f), 0.005f, 1),
            triangleAt(glm::vec3(0.9f, 0.4f, 0.4f), 0.005f, 2),
            triangleAt(glm::vec3(0.25f, 0.75f, 0.75f), 0.005f, 3)};
    // Cost 6: 3 <= 6 x 2, a leaf.
    EXPECT_EQ(build(input).nodes.size(), 1u);
    // Cost 1: 3 > 1 x 2 splits the root; 2 <= 1 x 2 and 1 <= 1 x 1 keep the children leaves.
    HierarchyParams cheapCubes;
    cheapCubes.cubeCost = 1.0f;
    const Built b = build(input, cheapCubes);
    ASSERT_EQ(b.nodes.size(), 3u);
    EXPECT_EQ(b.nodes[1].triangleCount, 2u);
    EXPECT_EQ(b.nodes[2].triangleCount, 1u);
    expectOctreeInvariants(b, input, cheapCubes);
}

TEST(OctreeBuilderTest, EmptyOctantsGetNoNodes) {
    // Many triangles in octants 2 and 5 only.
    const auto input = trianglesInOctants({{2, 40}, {5, 40}});
    const Built b = build(input);
    ASSERT_EQ(b.nodes[0].childCount, 2u);
    EXPECT_EQ(b.nodes[b.nodes[0].firstChild].octant, 2);
    EXPECT_EQ(b.nodes[b.nodes[0].firstChild + 1].octant, 5);
    expectOctreeInvariants(b, input, {});
}

bool ownsTriangle(const Built& b, const BuildNode& node, const storage::PackedTriangle& triangle) {
    for (const storage::PackedTriangle& t : own(b, node))
        if (std::memcmp(&t, &triangle, sizeof(t)) == 0)
            return true;
    return false;
}

// A triangle descends while it is no wider than tolerance x the cell it reaches, and stops at the
// first cell it is wider than.
TEST(OctreeBuilderTest, LargeTrianglesStayAtTheInnerNode) {
    std::vector<storage::PackedTriangle> input = trianglesInOctants({{0, 20}, {3, 20}, {6, 20}});
    const storage::PackedTriangle wider = triangleAt(glm::vec3(0.5f), 1.2f, 1000);   // > root
    const storage::PackedTriangle half = triangleAt(glm::vec3(0.3f), 0.75f, 1001);   // > 0.5
    const storage::PackedTriangle quarter = triangleAt(glm::vec3(0.2f), 0.4f, 1002); // > 0.25
    input.push_back(wider);
    input.push_back(half);
    input.push_back(quarter);
    const Built b = build(input);
    const BuildNode& root = b.nodes[0];
    ASSERT_GT(root.childCount, 0u);
    EXPECT_EQ(root.triangleCount, 1u);
    EXPECT_TRUE(ownsTriangle(b, root, wider));
    const BuildNode& child0 = b.nodes[root.firstChild];
    ASSERT_EQ(child0.octant, 0);
    ASSERT_GT(child0.childCount, 0u) << "21 triangles in two octants of the child should split";
    EXPECT_EQ(child0.triangleCount, 1u);
    EXPECT_TRUE(ownsTriangle(b, child0, half));
    const BuildNode& grandchild0 = b.nodes[child0.firstChild];
    ASSERT_EQ(grandchild0.octant, 0);
    EXPECT_EQ(grandchild0.childCount, 0u);
    EXPECT_EQ(grandchild0.triangleCount, 1u);
    EXPECT_TRUE(ownsTriangle(b, grandchild0, quarter));
    expectOctreeInvariants(b, input, {});

    // A larger tolerance lets the same triangles descend further.
    HierarchyParams tolerant;
    tolerant.largeTriangleTolerance = 2.0f;
    const Built t = build(input, tolerant);
    EXPECT_EQ(t.nodes[0].triangleCount, 0u);
    expectOctreeInvariants(t, input, tolerant);
}

TEST(OctreeBuilderTest, OnlyLargeTrianglesMakeALeaf) {
    std::vector<storage::PackedTriangle> input;
    for (int k = 0; k < 20; ++k)
        input.push_back(
                triangleAt(glm::vec3(0.5f, 0.5f, 0.05f * static_cast<float>(k) + 0.01f), 1.5f, k));
    const Built b = build(input);
    ASSERT_EQ(b.nodes.size(), 1u);
    EXPECT_EQ(b.nodes[0].triangleCount, 20u);
    expectOctreeInvariants(b, input, {});
}

TEST(OctreeBuilderTest, MaxDepthStopsCoincidentTriangles) {
    // 1e-4 wide: smaller than every cell down to level 13, so only maxDepth stops them.
    const std::vector<storage::PackedTriangle> input(
            50, triangleAt(glm::vec3(0.3f, 0.6f, 0.2f), 1e-4f));
    for (int maxDepth : {0, 1, 4, 12}) {
        SCOPED_TRACE(::testing::Message() << "maxDepth " << maxDepth);
        HierarchyParams params;
        params.maxDepth = maxDepth;
        const Built b = build(input, params);
        // One chain of single children down to maxDepth, whose leaf holds them all.
        ASSERT_EQ(b.nodes.size(), static_cast<std::size_t>(maxDepth) + 1);
        const BuildNode& leaf = b.nodes.back();
        EXPECT_EQ(leaf.level, maxDepth);
        EXPECT_EQ(leaf.childCount, 0u);
        EXPECT_EQ(leaf.triangleCount, 50u);
        expectOctreeInvariants(b, input, params);
    }
}

TEST(OctreeBuilderTest, SubtreeRootKeepsItsLevelAndOctant) {
    // A chunk root at level 3, octant 5, inside the cell [2, 2.5]^3.
    std::vector<storage::PackedTriangle> input;
    for (const storage::PackedTriangle& t : randomTriangles(400, 11)) {
        storage::PackedTriangle moved = t;
        for (storage::PackedVertex& v : moved.vertices)
            for (float& c : v.position)
                c = 2.0f + 0.5f * c;
        input.push_back(moved);
    }
    HierarchyParams params;
    params.maxDepth = 6;
    const Built b = build(input, params, {glm::vec3(2.0f), 0.5f}, 3, 5);
    EXPECT_EQ(b.nodes[0].level, 3);
    EXPECT_EQ(b.nodes[0].octant, 5);
    EXPECT_EQ(b.nodes[0].cellMin, glm::vec3(2.0f));
    EXPECT_EQ(b.nodes[0].cellMax, glm::vec3(2.5f));
    expectOctreeInvariants(b, input, params, 3);
}

TEST(OctreeBuilderTest, RandomSceneKeepsEveryInvariant) {
    const auto input = randomTriangles(5000, 7);
    HierarchyParams params;
    const Built b = build(input, params);
    EXPECT_GT(b.nodes.size(), 100u);
    expectOctreeInvariants(b, input, params);

    HierarchyParams direct;
    direct.bakeInnerDirect = true;
    expectOctreeInvariants(build(input, direct), input, direct);
}

TEST(OctreeBuilderTest, OutputIsDeterministic) {
    const auto input = randomTriangles(3000, 3);
    const Built a = build(input);
    const Built b = build(input);
    ASSERT_EQ(a.nodes.size(), b.nodes.size());
    ASSERT_EQ(a.triangles.size(), b.triangles.size());
    EXPECT_EQ(
            std::memcmp(
                    a.triangles.data(),
                    b.triangles.data(),
                    a.triangles.size() * sizeof(a.triangles[0])),
            0);
    for (std::size_t i = 0; i < a.nodes.size(); ++i) {
        EXPECT_EQ(a.nodes[i].firstChild, b.nodes[i].firstChild);
        EXPECT_EQ(a.nodes[i].firstTriangle, b.nodes[i].firstTriangle);
        EXPECT_EQ(quantizeCube(a.nodes[i].cube), quantizeCube(b.nodes[i].cube));
    }
}

TEST(OctreeBuilderTest, CubesAreBakedBottomUp) {
    const auto input = randomTriangles(800, 5);
    const HierarchyParams params;
    const Built b = build(input, params);
    CubeBaker baker(params.bakeResolution);
    for (const BuildNode& node : b.nodes) {
        baker.reset(node.cellMin, node.cellMax);
        baker.addTriangles(own(b, node));
        ColorCube expected;
        if (node.childCount == 0) {
            expected = baker.finish();
        } else {
            // Own (large) triangles over the children's Fig. 3 composite.
            std::array<const ColorCube*, 8> children{};
            for (std::uint32_t c = 0; c < node.childCount; ++c)
                children[b.nodes[node.firstChild + c].octant] = &b.nodes[node.firstChild + c].cube;
            const QuadrantColors underlay = compositeOctantQuadrants(children);
            expected = baker.finish(&underlay);
        }
        for (std::size_t f = 0; f < expected.faces.size(); ++f)
            EXPECT_EQ(node.cube.faces[f], expected.faces[f]);
    }
    // The triangles lie in z = const planes: seen along Z, edge-on along X and Y.
    EXPECT_GT(b.nodes[0].cube.faces[4].a, 0.0f);
    EXPECT_GT(b.nodes[0].cube.faces[5].a, 0.0f);
    EXPECT_EQ(b.nodes[0].cube.faces[0].a, 0.0f);
}

} // namespace
} // namespace ff::builder
