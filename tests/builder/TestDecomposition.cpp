// The decompositions (builder/src/Decomposition.h): every item in exactly one node, subtrees as
// ranges, the paper's limits honoured; and every decomposition end to end through the builder,
// on ordinary, instanced, out-of-core and degenerate inputs.

#include "BuiltScene.h"
#include "Decomposition.h"
#include "RecordingSink.h"

#include <ff/builder/HierarchyParams.h>
#include <ff/builder/SceneBuilder.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <fstream>
#include <iterator>
#include <numeric>
#include <set>
#include <string>
#include <tuple>
#include <vector>

namespace ff::builder {
namespace {

namespace fs = std::filesystem;
using namespace testing;

constexpr Decomposition kBoundingVolumes[] = {
        Decomposition::Dbvd, Decomposition::Phbvo, Decomposition::Balanced};
constexpr Decomposition kAll[] = {
        Decomposition::Octree,
        Decomposition::Dbvd,
        Decomposition::Phbvo,
        Decomposition::Balanced,
        Decomposition::Orsd};

std::string nameOf(Decomposition d) {
    return std::string(decompositionName(d));
}

/** Small items in a box, and a few long ones across it (the factory floor). */
std::vector<SplitItem> mixedItems(std::size_t count, std::uint64_t seed) {
    Lcg rng(seed);
    std::vector<SplitItem> items;
    for (std::size_t i = 0; i < count; ++i) {
        const glm::vec3 c = rng.inBox(glm::vec3(0.0f), glm::vec3(8.0f, 2.0f, 4.0f));
        items.push_back({c - glm::vec3(0.01f), c + glm::vec3(0.01f), c});
    }
    for (int k = 0; k < 16; ++k) {
        const float z = 0.25f * static_cast<float>(k);
        items.push_back(
                {glm::vec3(0.0f, 0.0f, z),
                 glm::vec3(8.0f, 0.1f, z + 0.1f),
                 glm::vec3(4.0f, 0.05f, z + 0.05f)});
    }
    return items;
}

/** Checks the SplitNode contract over `items` and returns the number of leaves. */
std::size_t expectValidTree(
        const std::vector<SplitNode>& nodes,
        const std::vector<std::uint32_t>& order,
        std::span<const SplitItem> items,
        const DecompositionParams& params) {
    std::vector<std::uint32_t> sorted = order;
    std::sort(sorted.begin(), sorted.end());
    std::vector<std::uint32_t> all(items.size());
    std::iota(all.begin(), all.end(), 0u);
    EXPECT_EQ(sorted, all) << "order is not a permutation of the items";
    EXPECT_EQ(nodes[0].begin, 0u);
    EXPECT_EQ(nodes[0].end, items.size());

    std::vector<int> owners(items.size(), 0);
    std::size_t leaves = 0;
    for (const SplitNode& node : nodes) {
        EXPECT_LE(node.begin, node.ownEnd);
        EXPECT_LE(node.ownEnd, node.end);
        EXPECT_LE(node.level, params.maxDepth);
        EXPECT_LE(node.childCount, 255u);
        for (std::uint64_t i = node.begin; i < node.ownEnd; ++i)
            ++owners[order[i]];
        for (std::uint64_t i = node.begin; i < node.end; ++i) {
            const SplitItem& item = items[order[i]];
            EXPECT_TRUE(
                    glm::all(glm::lessThanEqual(node.boundsMin, item.lo)) &&
                    glm::all(glm::greaterThanEqual(node.boundsMax, item.hi)))
                    << "an item pokes out of its node's bounds";
        }
        if (node.childCount == 0) {
            ++leaves;
            EXPECT_EQ(node.ownEnd, node.end) << "a leaf owns all its items";
            continue;
        }
        EXPECT_EQ(node.ownEnd, node.begin)
                << "inner nodes own nothing: pulled-up items get a geometry node";
        std::uint64_t cursor = node.ownEnd;
        for (std::uint32_t c = 0; c < node.childCount; ++c) {
            const SplitNode& child = nodes[node.firstChild + c];
            EXPECT_EQ(child.begin, cursor) << "children's ranges follow each other";
            EXPECT_GT(child.end, child.begin) << "no empty child";
            EXPECT_EQ(child.level, node.level + 1);
            cursor = child.end;
        }
        EXPECT_EQ(cursor, node.end);
    }
    EXPECT_TRUE(std::all_of(owners.begin(), owners.end(), [](int n) { return n == 1; }))
            << "an item is in no node or in two";
    return leaves;
}

TEST(DecompositionTest, EveryItemIsInExactlyOneNode) {
    const std::vector<SplitItem> items = mixedItems(20000, 3);
    DecompositionParams params;
    for (const Decomposition d : kBoundingVolumes) {
        SCOPED_TRACE(nameOf(d));
        std::vector<std::uint32_t> order;
        const std::vector<SplitNode> nodes = decompose(items, order, d, params);
        const std::size_t leaves = expectValidTree(nodes, order, items, params);
        EXPECT_GT(leaves, items.size() / 2048) << "the items were split";
    }
}

TEST(DecompositionTest, PhbvoHonoursMaxTrianglesAndArity) {
    const std::vector<SplitItem> items = mixedItems(20000, 5);
    for (const unsigned arity : {2u, 4u}) {
        SCOPED_TRACE(arity);
        DecompositionParams params;
        params.arity = arity;
        params.maxTriangles = 300;
        std::vector<std::uint32_t> order;
        const std::vector<SplitNode> nodes = decompose(items, order, Decomposition::Phbvo, params);
        expectValidTree(nodes, order, items, params);
        std::uint32_t widest = 0;
        for (const SplitNode& node : nodes) {
            widest = std::max(widest, node.childCount);
            if (node.childCount == 0) {
                EXPECT_LE(node.end - node.begin, params.maxTriangles);
            }
        }
        EXPECT_EQ(widest, arity);
    }
    // Max_Depth stops it whatever the count.
    DecompositionParams shallow;
    shallow.maxDepth = 2;
    shallow.maxTriangles = 1;
    std::vector<std::uint32_t> order;
    const std::vector<SplitNode> nodes = decompose(items, order, Decomposition::Phbvo, shallow);
    expectValidTree(nodes, order, items, shallow);
    EXPECT_LE(
            std::max_element(
                    nodes.begin(),
                    nodes.end(),
                    [](const SplitNode& a, const SplitNode& b) { return a.level < b.level; })
                    ->level,
            2);
}

TEST(DecompositionTest, PhbvoSeparatesTwoClustersAtTheGap) {
    // Two clumps far apart: the surface-area cost is least at the gap, not at the median.
    std::vector<SplitItem> items;
    Lcg rng(9);
    for (int i = 0; i < 3000; ++i) {
        const bool right = i % 4 == 0; // a quarter of them on the right
        const glm::vec3 c = rng.inBox(
                glm::vec3(right ? 90.0f : 0.0f, 0.0f, 0.0f),
                glm::vec3(right ? 100.0f : 10.0f, 10.0f, 10.0f));
        items.push_back({c - glm::vec3(0.05f), c + glm::vec3(0.05f), c});
    }
    DecompositionParams params;
    params.arity = 2;
    params.maxTriangles = 100;
    std::vector<std::uint32_t> order;
    const std::vector<SplitNode> nodes = decompose(items, order, Decomposition::Phbvo, params);
    ASSERT_EQ(nodes[0].childCount, 2u);
    const SplitNode& left = nodes[nodes[0].firstChild];
    const SplitNode& right = nodes[nodes[0].firstChild + 1];
    EXPECT_LT(left.boundsMax.x, 11.0f);
    EXPECT_GT(right.boundsMin.x, 89.0f);
    EXPECT_EQ(right.end - right.begin, 750u);
}

TEST(DecompositionTest, DbvdCutsTheLongestSideIntoCubeLikeSlabsAndPullsUpLongItems) {
    const std::vector<SplitItem> items = mixedItems(20000, 7); // an 8 x 2 x 4 box
    DecompositionParams params;
    std::vector<std::uint32_t> order;
    const std::vector<SplitNode> nodes = decompose(items, order, Decomposition::Dbvd, params);
    expectValidTree(nodes, order, items, params);
    const SplitNode& root = nodes[0];
    // Equation (1): largest / second-largest = 8 / 4 = 2 slabs, plus the geometry node first.
    ASSERT_EQ(root.childCount, 3u);
    const SplitNode& floor = nodes[root.firstChild];
    EXPECT_EQ(floor.childCount, 0u);
    EXPECT_EQ(floor.end - floor.begin, 16u) << "the 16 long items, pulled up";
    for (std::uint64_t i = floor.begin; i < floor.end; ++i)
        EXPECT_GE(order[i], 20000u);
    const SplitNode& first = nodes[root.firstChild + 1];
    const SplitNode& second = nodes[root.firstChild + 2];
    // The plane starts at x = 4 and may move a quarter slab to cut fewer items.
    EXPECT_NEAR(first.boundsMax.x, 4.0f, 1.05f);
    EXPECT_NEAR(second.boundsMin.x, first.boundsMax.x, 0.05f);
    for (const SplitNode& node : nodes)
        if (node.childCount == 0 && node.end - node.begin > params.minTriangles) {
            EXPECT_TRUE(&node == &floor || node.level == params.maxDepth)
                    << "leaves stop at minTriangles";
        }
}

TEST(DecompositionTest, DbvdMovesThePlaneToCutFewerItems) {
    // Bands of items one unit apart along x, 5 units tall: two slabs, the even plane at x = 5
    // runs through a band, so both slabs take part of it and their boxes overlap. Moved into a
    // gap, the plane cuts nothing and the boxes are apart.
    std::vector<SplitItem> items;
    Lcg rng(13);
    for (int band = 0; band <= 10; ++band)
        for (int k = 0; k <= 100; ++k) {
            const glm::vec3 c(
                    static_cast<float>(band) + 0.2f * (rng.next() - 0.5f),
                    0.05f * static_cast<float>(k),
                    0.0f);
            items.push_back(
                    {c - glm::vec3(0.2f, 0.004f, 0.004f), c + glm::vec3(0.2f, 0.004f, 0.004f), c});
        }
    auto slabsOverlap = [&](float planeShift) {
        DecompositionParams params;
        params.minTriangles = 800; // the root splits, its slabs do not
        params.planeShift = planeShift;
        std::vector<std::uint32_t> order;
        const std::vector<SplitNode> nodes = decompose(items, order, Decomposition::Dbvd, params);
        expectValidTree(nodes, order, items, params);
        EXPECT_EQ(nodes[0].childCount, 2u);
        const SplitNode& a = nodes[nodes[0].firstChild];
        const SplitNode& b = nodes[nodes[0].firstChild + 1];
        return a.boundsMax.x > b.boundsMin.x;
    };
    EXPECT_TRUE(slabsOverlap(0.0f));
    EXPECT_FALSE(slabsOverlap(0.25f));
}

TEST(DecompositionTest, BalancedSplitsEightWaysAtMediansAndHonoursTriMin) {
    const std::vector<SplitItem> items = mixedItems(20000, 11);
    DecompositionParams params;
    params.maxTriangles = 1000;
    params.balancedMinTriangles = 200;
    std::vector<std::uint32_t> order;
    const std::vector<SplitNode> nodes = decompose(items, order, Decomposition::Balanced, params);
    expectValidTree(nodes, order, items, params);
    EXPECT_EQ(nodes[0].childCount, 8u);
    for (const SplitNode& node : nodes) {
        if (node.childCount == 0) {
            EXPECT_LE(node.end - node.begin, params.maxTriangles);
        }
        if (&node != &nodes[0]) {
            EXPECT_GE(node.end - node.begin, params.balancedMinTriangles / 2)
                    << "medians keep loads even";
        }
    }
    for (std::uint32_t c = 0; c < 8; ++c)
        EXPECT_NEAR(
                static_cast<double>(
                        nodes[nodes[0].firstChild + c].end - nodes[nodes[0].firstChild + c].begin),
                static_cast<double>(items.size()) / 8.0,
                1.0);
}

TEST(DecompositionTest, OrsdSplitsBlocksByRelevantCellsAndKeepsItemsInTheirBlock) {
    VoxelGrid grid;
    grid.origin = glm::vec3(-1.0f);
    grid.cellSize = 0.5f;
    grid.cells = glm::uvec3(24, 16, 20);
    const GridBlock root = rootGridBlock(grid);
    EXPECT_EQ(root.size, 32u);
    // A shell of relevant cells: several items in each cell the sphere passes through.
    std::vector<SplitItem> items;
    for (std::uint32_t x = 0; x < 24; ++x)
        for (std::uint32_t y = 0; y < 16; ++y)
            for (std::uint32_t z = 0; z < 20; ++z) {
                const glm::vec3 centre = grid.origin + (glm::vec3(x, y, z) + 0.5f) * grid.cellSize;
                const float r = glm::length(centre - glm::vec3(5.0f, 3.0f, 4.0f));
                if (std::abs(r - 3.0f) > 0.3f)
                    continue;
                for (int k = 0; k < 3; ++k) {
                    const glm::vec3 c = centre + glm::vec3(0.1f * static_cast<float>(k - 1));
                    items.push_back({c - glm::vec3(0.05f), c + glm::vec3(0.05f), c});
                }
            }
    DecompositionParams params;
    params.relevantCells = 40;
    std::vector<std::uint32_t> order;
    const std::vector<SplitNode> nodes =
            decompose(items, order, Decomposition::Orsd, params, &grid, root);
    expectValidTree(nodes, order, items, params);
    for (const SplitNode& node : nodes) {
        // The block: a power-of-two cube of cells holding every item's centre.
        const glm::vec3 edge = (node.cellMax - node.cellMin) / grid.cellSize;
        EXPECT_FLOAT_EQ(edge.x, edge.y);
        EXPECT_TRUE(std::has_single_bit(static_cast<unsigned>(std::lround(edge.x))));
        for (std::uint64_t i = node.begin; i < node.end; ++i)
            EXPECT_TRUE(
                    glm::all(glm::lessThanEqual(node.cellMin, items[order[i]].centre)) &&
                    glm::all(glm::lessThan(items[order[i]].centre, node.cellMax)));
        if (node.childCount > 0) {
            EXPECT_TRUE(node.octreeChildren);
            for (std::uint32_t c = 1; c < node.childCount; ++c)
                EXPECT_LT(nodes[node.firstChild + c - 1].octant, nodes[node.firstChild + c].octant);
        }
        // Relevant cells of a leaf: at most the threshold, unless it is one cell.
        if (node.childCount == 0 && edge.x > 1.5f) {
            std::set<std::tuple<int, int, int>> cells;
            for (std::uint64_t i = node.begin; i < node.end; ++i) {
                const glm::ivec3 cell((items[order[i]].centre - grid.origin) / grid.cellSize);
                cells.insert({cell.x, cell.y, cell.z});
            }
            EXPECT_LE(cells.size(), params.relevantCells);
        }
    }
    EXPECT_GT(nodes.size(), 8u);
}

TEST(DecompositionTest, GridBlocksAreRecognisedOnlyWhenAligned) {
    VoxelGrid grid;
    grid.origin = glm::vec3(1.0f, 2.0f, 3.0f);
    grid.cellSize = 0.25f;
    grid.cells = glm::uvec3(64u);
    const std::optional<GridBlock> block =
            gridBlockOf(grid, grid.origin + glm::vec3(2.0f, 0.0f, 4.0f), 2.0f);
    ASSERT_TRUE(block.has_value());
    EXPECT_EQ(block->size, 8u);
    EXPECT_EQ(block->first, glm::uvec3(8u, 0u, 16u));
    EXPECT_FALSE(gridBlockOf(grid, grid.origin + glm::vec3(0.25f, 0.0f, 0.0f), 2.0f))
            << "not aligned to its size";
    EXPECT_FALSE(gridBlockOf(grid, grid.origin, 1.5f)) << "not a power of two";
}

TEST(DecompositionTest, NamesRoundTrip) {
    for (const Decomposition d : kAll)
        EXPECT_EQ(parseDecomposition(decompositionName(d)), d);
    EXPECT_FALSE(parseDecomposition("kd-tree").has_value());
}

// ---- through the builder ---------------------------------------------------------------------

BuildOptions optionsFor(Decomposition d, unsigned threads = 1) {
    BuildOptions options = smallOptions(threads);
    options.hierarchy.decomposition = d;
    return options;
}

/** The scene with a voxel grid of 16 cells an axis over its bounds (ORSD needs one). */
RecordingSink withGrid(RecordingSink scene) {
    for (PrototypeId p = 0; p < scene.prototypes().size(); ++p) {
        glm::vec3 lo(std::numeric_limits<float>::infinity());
        glm::vec3 hi(-std::numeric_limits<float>::infinity());
        for (const storage::PackedTriangle& t : scene.prototypes()[p].triangles)
            for (const storage::PackedVertex& v : t.vertices) {
                lo = glm::min(lo, glm::vec3(v.position[0], v.position[1], v.position[2]));
                hi = glm::max(hi, glm::vec3(v.position[0], v.position[1], v.position[2]));
            }
        const glm::vec3 size = hi - lo;
        VoxelGrid grid;
        grid.origin = lo;
        grid.cellSize = std::max({size.x, size.y, size.z, 1e-3f}) / 16.0f * 1.001f;
        grid.cells = glm::uvec3(16u);
        EXPECT_TRUE(scene.declareVoxelGrid(p, grid).isOk());
    }
    return scene;
}

TEST(DecompositionBuildTest, EveryDecompositionStoresEveryTriangleOnce) {
    std::vector<storage::PackedTriangle> triangles =
            cluster(6000, glm::vec3(0.0f), glm::vec3(4.0f, 1.0f, 2.0f), 1);
    for (int k = 0; k < 12; ++k) // long ones, pulled up by D-BVD, kept high by the octree
        triangles.push_back(triangleAt(glm::vec3(2.0f, 0.5f, 0.15f * static_cast<float>(k)), 3.5f));
    const RecordingSink scene = withGrid(singlePrototypeScene(triangles));
    for (const Decomposition d : kAll) {
        SCOPED_TRACE(nameOf(d));
        const fs::path dir = freshTestDir() / nameOf(d);
        fs::create_directories(dir);
        BuildOptions options = optionsFor(d);
        options.hierarchy.split.relevantCells = 32; // the 16-cell grid splits more than once
        const BuildReport report = buildOrFail(scene, dir / "scene.ffs", options);
        EXPECT_EQ(report.decomposition, nameOf(d));
        EXPECT_GT(report.nodes, 8u);
        EXPECT_GT(report.leafNodes, 4u);
        EXPECT_LT(report.leafNodes, report.nodes);
        expectSceneMatches(dir / "scene.ffs", scene, report);
    }
}

TEST(DecompositionBuildTest, InstanceLevelIsDecomposedToo) {
    const RecordingSink scene = generate("molecule:spheres=300");
    for (const Decomposition d : kBoundingVolumes) {
        SCOPED_TRACE(nameOf(d));
        const fs::path dir = freshTestDir() / nameOf(d);
        fs::create_directories(dir);
        const BuildReport report = buildOrFail(scene, dir / "scene.ffs", optionsFor(d));
        EXPECT_GT(report.instanceLevelDepth, 1u);
        expectSceneMatches(dir / "scene.ffs", scene, report);
    }
}

TEST(DecompositionBuildTest, OutOfCoreChunksAreDecomposed) {
    constexpr unsigned kThreads = 4;
    const RecordingSink scene = generate("terrain:triangles=60000");
    for (const Decomposition d : kBoundingVolumes) {
        SCOPED_TRACE(nameOf(d));
        const fs::path dir = freshTestDir() / nameOf(d);
        fs::create_directories(dir);
        const BuildReport first = buildOrFail(scene, dir / "a.ffs", optionsFor(d, kThreads));
        EXPECT_GT(first.chunks, 1u);
        expectSceneMatches(dir / "a.ffs", scene, first);
        // Deterministic, whichever thread built which chunk.
        buildOrFail(scene, dir / "b.ffs", optionsFor(d, kThreads));
        std::ifstream a(dir / "a.ffs", std::ios::binary);
        std::ifstream b(dir / "b.ffs", std::ios::binary);
        EXPECT_TRUE(std::equal(
                std::istreambuf_iterator<char>(a), {}, std::istreambuf_iterator<char>(b), {}));
    }
}

TEST(DecompositionBuildTest, OrsdRefusesInputsWithoutAVoxelGrid) {
    const fs::path dir = freshTestDir();
    const RecordingSink scene =
            singlePrototypeScene(cluster(100, glm::vec3(0.0f), glm::vec3(1.0f), 2));
    Result<BuildReport> report =
            buildScene(scene, dir / "scene.ffs", optionsFor(Decomposition::Orsd));
    ASSERT_FALSE(report.isOk());
    EXPECT_EQ(report.status().code(), ErrorCode::InvalidArgument);
    EXPECT_NE(report.status().message().find("needs a voxel grid"), std::string::npos)
            << report.status().message();
    EXPECT_FALSE(fs::exists(dir / "scene.ffs"));
}

// ---- degenerate inputs -----------------------------------------------------------------------

std::vector<storage::PackedTriangle> coplanarTriangles() {
    Lcg rng(4);
    std::vector<storage::PackedTriangle> out;
    for (int i = 0; i < 5000; ++i) {
        const glm::vec3 c = rng.inBox(glm::vec3(0.0f), glm::vec3(10.0f, 10.0f, 0.0f));
        out.push_back(packTriangle(
                vertexAt(c),
                vertexAt(c + glm::vec3(0.05f, 0.0f, 0.0f)),
                vertexAt(c + glm::vec3(0.0f, 0.05f, 0.0f))));
    }
    return out;
}

void expectEveryDecompositionBuilds(
        const std::vector<storage::PackedTriangle>& triangles, std::uint64_t budget) {
    const RecordingSink scene = withGrid(singlePrototypeScene(triangles));
    for (const Decomposition d : kAll) {
        SCOPED_TRACE(nameOf(d));
        const fs::path dir = freshTestDir() / nameOf(d);
        fs::create_directories(dir);
        BuildOptions options = optionsFor(d);
        options.memoryBudgetBytes = budget;
        options.pageSize = storage::kDefaultPageSize;
        const BuildReport report = buildOrFail(scene, dir / "scene.ffs", options);
        EXPECT_EQ(report.storedTriangles, triangles.size());
        expectSceneMatches(dir / "scene.ffs", scene, report);
    }
}

TEST(DecompositionBuildTest, DegenerateAllCoplanar) {
    expectEveryDecompositionBuilds(coplanarTriangles(), SceneBuilder::kMinimumBudgetBytes);
}

TEST(DecompositionBuildTest, DegenerateOneHugeTriangle) {
    expectEveryDecompositionBuilds(
            {packTriangle(
                    vertexAt(glm::vec3(-1e6f, 0.0f, -1e6f)),
                    vertexAt(glm::vec3(1e6f, 0.0f, -1e6f)),
                    vertexAt(glm::vec3(0.0f, 1e3f, 1e6f)))},
            SceneBuilder::kMinimumBudgetBytes);
}

TEST(DecompositionBuildTest, DegenerateSingleTriangle) {
    expectEveryDecompositionBuilds(
            {triangleAt(glm::vec3(1.0f, 2.0f, 3.0f), 0.1f)}, SceneBuilder::kMinimumBudgetBytes);
}

TEST(DecompositionBuildTest, DegenerateManyIdenticalTriangles) {
    // No plane separates them: every decomposition must fall back to splitting the list.
    const std::vector<storage::PackedTriangle> triangles(20'000, triangleAt(glm::vec3(0.5f), 0.2f));
    expectEveryDecompositionBuilds(triangles, SceneBuilder::kMinimumBudgetBytes << 2);
}

// The size. Run by scripts/test.sh on the plain build only: under the sanitizers it
// takes minutes, and DegenerateManyIdenticalTriangles runs the same paths there.
TEST(DecompositionBuildTest, DegenerateAMillionIdenticalTriangles) {
    // In one chunk (no cell could split them): a budget that holds them.
    const std::vector<storage::PackedTriangle> triangles(
            1'000'000, triangleAt(glm::vec3(0.5f), 0.2f));
    expectEveryDecompositionBuilds(triangles, 1ull << 30);
}

} // namespace
} // namespace ff::builder
