// Cluster nodes (builder/src/ClusterNodes.h): format 2's leaves get a tree of nodes over their
// clusters, so a cut can stop inside a leaf. Every triangle stays reachable exactly once, each
// piece is about a cluster inside its parent's bounds with an opaque cube of its own, and the
// result does not depend on the threads.

#include "ClusterNodes.h"
#include "OctreeBuilder.h"
#include "GeneratedTriangles.h"

#include <ff/builder/ColorCube.h>
#include <ff/builder/Generators.h>
#include <ff/builder/HierarchyParams.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <string>
#include <vector>

namespace ff::builder {
namespace {

using testing::generatedTriangles;

struct Shaped {
    std::vector<BuildNode> nodes;
    std::vector<storage::PackedTriangle> triangles;
    storage::PositionGrid grid;
};

Shaped
shape(const std::string& scene, std::uint64_t leafTriangles, bool clusterNodes, unsigned threads) {
    Shaped out;
    out.triangles = generatedTriangles(scene);
    glm::vec3 lo(std::numeric_limits<float>::max());
    glm::vec3 hi(std::numeric_limits<float>::lowest());
    for (const auto& t : out.triangles)
        growBounds(lo, hi, t);
    auto grid = storage::PositionGrid::covering({lo.x, lo.y, lo.z}, {hi.x, hi.y, hi.z});
    EXPECT_TRUE(grid.isOk());
    out.grid = *grid;
    const glm::vec3 size = hi - lo;
    const Cell root{lo, std::max({size.x, size.y, size.z}) * 1.0001f};
    HierarchyParams params;
    CubeBaker baker(params.bakeResolution);
    out.nodes = buildOctree(out.triangles, root, 0, 0, params, baker);
    LeafShapeV2 leafShape;
    leafShape.leafTriangles = leafTriangles;
    leafShape.clusterNodes = clusterNodes;
    leafShape.grid = &out.grid;
    leafShape.threads = threads;
    EXPECT_TRUE(shapeLeavesV2(out.nodes, out.triangles, leafShape).isOk());
    return out;
}

std::vector<std::uint32_t> reachable(const std::vector<BuildNode>& nodes) {
    std::vector<std::uint32_t> out{0};
    for (std::size_t i = 0; i < out.size(); ++i)
        for (std::uint32_t c = 0; c < nodes[out[i]].childCount; ++c)
            out.push_back(nodes[out[i]].firstChild + c);
    return out;
}

std::uint64_t
clustersOf(std::span<const storage::PackedTriangle> triangles, const storage::PositionGrid& grid) {
    std::vector<std::byte> bytes;
    const auto stats = ClusterEncoder().encode(triangles, grid, bytes);
    EXPECT_TRUE(stats.isOk());
    return stats.isOk() ? stats->clusters : 0;
}

bool inside(const glm::vec3& lo, const glm::vec3& hi, const BuildNode& outer) {
    for (int a = 0; a < 3; ++a)
        if (lo[a] < outer.boundsMin[a] || hi[a] > outer.boundsMax[a])
            return false;
    return true;
}

TEST(ClusterNodesTest, EveryLeafIsAboutAClusterInsideItsParentWithACubeOfItsOwn) {
    const Shaped s = shape("terrain:triangles=60000", 4096, true, 1);
    std::uint64_t reached = 0;
    std::uint64_t clusterLeaves = 0;
    std::uint64_t clusters = 0;
    for (const std::uint32_t n : reachable(s.nodes)) {
        const BuildNode& node = s.nodes[n];
        const auto own = std::span(s.triangles).subspan(node.firstTriangle, node.triangleCount);
        reached += node.triangleCount;
        glm::vec3 lo(std::numeric_limits<float>::max());
        glm::vec3 hi(std::numeric_limits<float>::lowest());
        for (const auto& t : own)
            growBounds(lo, hi, t);
        EXPECT_TRUE(own.empty() || inside(lo, hi, node)) << "node " << n;
        if (node.childCount > 0) {
            for (std::uint32_t c = 0; c < node.childCount; ++c) {
                const BuildNode& child = s.nodes[node.firstChild + c];
                EXPECT_TRUE(inside(child.boundsMin, child.boundsMax, node)) << "child of " << n;
            }
            continue;
        }
        const std::uint64_t k = clustersOf(own, s.grid);
        EXPECT_GE(k, 1u) << "leaf " << n;
        EXPECT_LE(k, 2u) << "leaf " << n;
        clusters += k;
        ++clusterLeaves;
        // The terrain seen from above (+Y): a compact piece covers most of its box's top face (cut
        // by centroids, a border row of samples may fall between its jagged edge and the box).
        EXPECT_GT(node.cube.faces[3].a, 0.8f) << "a cluster's cube must show it (leaf " << n << ")";
    }
    EXPECT_EQ(reached, s.triangles.size()); // each triangle in exactly one reachable run
    EXPECT_GT(clusterLeaves, 60000u / 256u);
    // Pieces cut in space rather than by the meshlet builder: a few more clusters, not many.
    EXPECT_LE(static_cast<double>(clusters), 1.15 * static_cast<double>(clusterLeaves));
}

TEST(ClusterNodesTest, WithoutClusterNodesALeafDrawsAllItsClusters) {
    const Shaped s = shape("terrain:triangles=60000", 4096, false, 1);
    std::uint64_t multiCluster = 0;
    for (const std::uint32_t n : reachable(s.nodes)) {
        const BuildNode& node = s.nodes[n];
        if (node.childCount == 0)
            multiCluster +=
                    clustersOf(
                            std::span(s.triangles).subspan(node.firstTriangle, node.triangleCount),
                            s.grid) > 1;
    }
    EXPECT_GT(multiCluster, 0u);
}

TEST(ClusterNodesTest, ALeafOfManyClustersBecomesAFourWayTree) {
    // The whole terrain one leaf: ~330 clusters under a tree at most four wide, whose inner nodes
    // draw nothing of their own but show their part of the terrain with their cubes.
    const Shaped s = shape("terrain:triangles=60000", 1u << 20, true, 1);
    ASSERT_GT(s.nodes[0].childCount, 0u);
    std::uint64_t clusters = 0;
    std::uint64_t pieces = 0;
    std::uint32_t deepest = 0;
    const std::vector<std::uint32_t> all = reachable(s.nodes);
    for (const std::uint32_t n : all) {
        const BuildNode& node = s.nodes[n];
        deepest = std::max<std::uint32_t>(deepest, node.level);
        EXPECT_LE(node.childCount, kClusterNodeBranching) << "node " << n;
        if (node.childCount > 0) {
            EXPECT_EQ(node.triangleCount, 0u) << "node " << n;
            // The split leaf (the root here) keeps the octree's cube; the nodes below it are
            // baked on their own bounds.
            if (n != 0) {
                EXPECT_GT(node.cube.faces[3].a, 0.8f) << "node " << n;
            }
            continue;
        }
        const auto k = clustersOf(
                std::span(s.triangles).subspan(node.firstTriangle, node.triangleCount), s.grid);
        EXPECT_GE(k, 1u) << "piece " << n;
        EXPECT_LE(k, 3u) << "piece " << n;
        clusters += k;
        ++pieces;
    }
    EXPECT_GT(clusters, 255u);
    // Pieces a little smaller than the meshlet builder's average fit one cluster each (of the
    // average size, a slab's jagged edge overflows the vertex limit: 1.9 clusters a piece).
    EXPECT_LE(static_cast<double>(clusters), 1.1 * static_cast<double>(pieces));
    // A tree: no node reached twice (a wrong firstChild would share or skip children).
    std::vector<std::uint32_t> sorted = all;
    std::sort(sorted.begin(), sorted.end());
    EXPECT_EQ(std::adjacent_find(sorted.begin(), sorted.end()), sorted.end());
    // Balanced: log4 of the pieces, rounded up, levels below the leaf (one more for an uneven cut).
    std::uint32_t levels = 0;
    for (std::uint64_t span = 1; span < pieces; span *= kClusterNodeBranching)
        ++levels;
    EXPECT_LE(deepest, levels + 1);
}

TEST(ClusterNodesTest, TheThreadsChangeNothing) {
    const Shaped one = shape("sphere:triangles=40000", 4096, true, 1);
    const Shaped two = shape("sphere:triangles=40000", 4096, true, 2);
    ASSERT_EQ(one.nodes.size(), two.nodes.size());
    for (std::size_t n = 0; n < one.nodes.size(); ++n) {
        EXPECT_EQ(one.nodes[n].firstChild, two.nodes[n].firstChild);
        EXPECT_EQ(one.nodes[n].childCount, two.nodes[n].childCount);
        EXPECT_EQ(one.nodes[n].firstTriangle, two.nodes[n].firstTriangle);
        EXPECT_EQ(one.nodes[n].triangleCount, two.nodes[n].triangleCount);
        EXPECT_EQ(quantizeCube(one.nodes[n].cube), quantizeCube(two.nodes[n].cube));
    }
    ASSERT_EQ(one.triangles.size(), two.triangles.size());
    EXPECT_EQ(
            0,
            std::memcmp(
                    one.triangles.data(),
                    two.triangles.data(),
                    one.triangles.size() * sizeof(storage::PackedTriangle)));
}

} // namespace
} // namespace ff::builder
