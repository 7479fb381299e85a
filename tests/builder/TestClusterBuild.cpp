#include <ff/builder/ClusterBuild.h>
#include "GeneratedTriangles.h"

#include <ff/builder/Generators.h>
#include <ff/storage/ClusterCodec.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <iostream>
#include <map>
#include <string>
#include <tuple>
#include <vector>

namespace ff::builder {
namespace {

using testing::generatedTriangles;

storage::PositionGrid gridOver(std::span<const storage::PackedTriangle> triangles) {
    std::array<float, 3> lo{INFINITY, INFINITY, INFINITY};
    std::array<float, 3> hi{-INFINITY, -INFINITY, -INFINITY};
    for (const auto& t : triangles)
        for (const auto& v : t.vertices)
            for (std::size_t a = 0; a < 3; ++a) {
                lo[a] = std::min(lo[a], v.position[a]);
                hi[a] = std::max(hi[a], v.position[a]);
            }
    auto grid = storage::PositionGrid::covering(lo, hi);
    EXPECT_TRUE(grid.isOk());
    return *grid;
}

/** Triangles in leaf-sized pieces, as a hierarchy's leaves would hand them over: bucketed by
 *  the cube of `cell` units their first corner lies in. */
std::vector<std::vector<storage::PackedTriangle>>
leaves(std::span<const storage::PackedTriangle> triangles, float cell) {
    std::map<std::array<long, 3>, std::vector<storage::PackedTriangle>> buckets;
    for (const auto& t : triangles) {
        std::array<long, 3> key{};
        for (std::size_t a = 0; a < 3; ++a)
            key[a] = std::lround(std::floor(t.vertices[0].position[a] / cell));
        buckets[key].push_back(t);
    }
    std::vector<std::vector<storage::PackedTriangle>> out;
    for (auto& [key, bucket] : buckets)
        out.push_back(std::move(bucket));
    return out;
}

using Corner =
        std::tuple<std::array<float, 3>, std::array<std::int16_t, 2>, std::array<std::uint8_t, 4>>;
using Triangle = std::array<Corner, 3>;

/** A triangle starting at its smallest corner (the index codec may rotate; winding stays). */
Triangle canonical(Triangle t) {
    std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
    return t;
}

std::vector<Triangle>
decodeAll(std::span<const std::byte> bytes, const storage::PositionGrid& grid) {
    std::vector<Triangle> out;
    std::vector<storage::PackedVertex> vertices(storage::kMaxClusterVertices);
    std::vector<std::uint8_t> indices(storage::kMaxClusterTriangles * 3);
    while (!bytes.empty()) {
        const auto info = storage::readClusterInfo(bytes);
        EXPECT_TRUE(info.isOk()) << info.status().toString();
        if (!info.isOk())
            break;
        const Status decoded = storage::decodeCluster(bytes, grid, vertices, indices);
        EXPECT_TRUE(decoded.isOk()) << decoded.toString();
        for (std::size_t t = 0; t < info->triangleCount; ++t) {
            Triangle tri;
            for (std::size_t c = 0; c < 3; ++c) {
                const auto& v = vertices[indices[3 * t + c]];
                tri[c] = {v.position, v.normalOct, v.color};
            }
            out.push_back(canonical(tri));
        }
        bytes = bytes.subspan(info->encodedBytes);
    }
    return out;
}

/** What the clusters must hold: each input triangle as quantized, collapsed ones left out. */
std::vector<Triangle>
expected(std::span<const storage::PackedTriangle> triangles, const storage::PositionGrid& grid) {
    std::vector<Triangle> out;
    for (const auto& t : triangles) {
        Triangle tri;
        std::array<std::array<std::uint32_t, 3>, 3> q{};
        for (std::size_t c = 0; c < 3; ++c) {
            q[c] = grid.quantize(t.vertices[c].position);
            tri[c] = {
                    grid.position(q[c]),
                    storage::roundNormalTo12Bits(t.vertices[c].normalOct),
                    t.vertices[c].color};
        }
        if (q[0] != q[1] && q[1] != q[2] && q[0] != q[2])
            out.push_back(canonical(tri));
    }
    return out;
}

// The terrain and the sphere, cut into leaf-sized pieces (an eighth of the extent a side): every
// triangle comes back exactly as quantized (positions within the grid's bound of the input), in
// under 8 bytes a triangle of cluster bytes (FORMAT v1 stores 60). The node records and page slack
// come on top.
TEST(ClusterBuildTest, TerrainAndSphereComeBackAsQuantizedInUnderEightBytesATriangle) {
    for (const char* scene : {"terrain:triangles=200000", "sphere:triangles=100000"}) {
        SCOPED_TRACE(scene);
        const auto triangles = generatedTriangles(scene);
        ASSERT_FALSE(triangles.empty());
        const storage::PositionGrid grid = gridOver(triangles);
        ClusterEncoder encoder;
        ClusterBuildStats total;
        std::vector<Triangle> want;
        std::vector<Triangle> got;
        for (const auto& leaf :
             leaves(triangles, grid.step * static_cast<float>(1 << grid.bits) / 8.0f)) {
            std::vector<std::byte> bytes;
            const auto stats = encoder.encode(leaf, grid, bytes);
            ASSERT_TRUE(stats.isOk()) << stats.status().toString();
            EXPECT_EQ(stats->encodedBytes, bytes.size());
            total += *stats;
            const auto decoded = decodeAll(bytes, grid);
            got.insert(got.end(), decoded.begin(), decoded.end());
            const auto wanted = expected(leaf, grid);
            want.insert(want.end(), wanted.begin(), wanted.end());
        }
        std::sort(want.begin(), want.end());
        std::sort(got.begin(), got.end());
        EXPECT_EQ(got.size(), total.trianglesKept);
        EXPECT_TRUE(got == want) << "the decoded triangles are not the quantized input";
        EXPECT_EQ(total.trianglesIn, triangles.size());
        EXPECT_GE(total.trianglesKept, triangles.size() * 999 / 1000);
        const double bytesPerTriangle =
                static_cast<double>(total.encodedBytes) / static_cast<double>(total.trianglesKept);
        RecordProperty("bytes_per_triangle", std::to_string(bytesPerTriangle));
        std::cout << scene << ": " << bytesPerTriangle << " bytes a triangle, " << total.clusters
                  << " clusters, " << total.wideClusters << " wide, "
                  << static_cast<double>(total.clusterVertices) /
                             static_cast<double>(total.trianglesKept)
                  << " vertices a triangle\n";
        EXPECT_LT(bytesPerTriangle, 8.0);
        for (const auto& t : got)
            for (const auto& c : t)
                for (std::size_t a = 0; a < 3; ++a)
                    EXPECT_TRUE(std::isfinite(std::get<0>(c)[a]));
    }
}

TEST(ClusterBuildTest, TheSameTrianglesGiveTheSameBytes) {
    const auto triangles = generatedTriangles("sphere:triangles=5000");
    const storage::PositionGrid grid = gridOver(triangles);
    std::vector<std::byte> a;
    std::vector<std::byte> b;
    ClusterEncoder first;
    ClusterEncoder second;
    ASSERT_TRUE(first.encode(triangles, grid, a).isOk());
    ASSERT_TRUE(first.encode(triangles, grid, b).isOk()); // scratch reused
    EXPECT_EQ(a, b);
    b.clear();
    ASSERT_TRUE(second.encode(triangles, grid, b).isOk());
    EXPECT_EQ(a, b);
}

// Cluster nodes (builder/src/ClusterNodes.h) give a leaf as many children as it has clusters.
TEST(ClusterBuildTest, CountClustersIsWhatEncodeMakes) {
    for (const char* scene : {"terrain:triangles=20000", "sphere:triangles=8000"}) {
        SCOPED_TRACE(scene);
        const auto triangles = generatedTriangles(scene);
        const storage::PositionGrid grid = gridOver(triangles);
        ClusterEncoder encoder;
        std::vector<std::byte> bytes;
        const auto stats = encoder.encode(triangles, grid, bytes);
        ASSERT_TRUE(stats.isOk());
        const auto count = encoder.countClusters(triangles, grid);
        ASSERT_TRUE(count.isOk());
        EXPECT_EQ(*count, stats->clusters);
        EXPECT_GT(*count, 10u);
        EXPECT_EQ(*encoder.countClusters({}, grid), 0u);
    }
}

// A triangle smaller than a grid step collapses onto fewer than three grid points: dropped,
// counted, and the rest still encode.
TEST(ClusterBuildTest, TrianglesQuantizationCollapsesAreDropped) {
    auto triangles = generatedTriangles("sphere:triangles=500");
    storage::PackedTriangle tiny = triangles[0];
    tiny.vertices[1].position = tiny.vertices[0].position;
    tiny.vertices[1].position[0] += 1e-7f;
    tiny.vertices[2].position = tiny.vertices[0].position;
    tiny.vertices[2].position[1] += 1e-7f;
    triangles.push_back(tiny);
    const storage::PositionGrid grid = gridOver(triangles);
    std::vector<std::byte> bytes;
    const auto stats = ClusterEncoder().encode(triangles, grid, bytes);
    ASSERT_TRUE(stats.isOk());
    EXPECT_EQ(stats->trianglesIn, triangles.size());
    EXPECT_EQ(stats->trianglesKept, triangles.size() - 1);
    EXPECT_EQ(decodeAll(bytes, grid).size(), triangles.size() - 1);
}

TEST(ClusterBuildTest, LimitsOutsideMeshoptimizersAreRefused) {
    const auto triangles = generatedTriangles("sphere:triangles=100");
    const storage::PositionGrid grid = gridOver(triangles);
    std::vector<std::byte> bytes;
    EXPECT_FALSE(ClusterEncoder({256, 256}).encode(triangles, grid, bytes).isOk());
    EXPECT_FALSE(ClusterEncoder({64, 126}).encode(triangles, grid, bytes).isOk());
    EXPECT_FALSE(ClusterEncoder({64, 516}).encode(triangles, grid, bytes).isOk());
    EXPECT_TRUE(ClusterEncoder({64, 124}).encode(triangles, grid, bytes).isOk());
}

} // namespace
} // namespace ff::builder
