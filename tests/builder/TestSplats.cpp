// Static point splats (builder/src/Splats.h): the stratification keeps its coverage guarantee
// and never deletes the last cover of a point it deleted; a splat set covers its surface within
// the radius it promises, keeps large triangles as triangles, and filters colours locally.

#include "Splats.h"

#include <ff/storage/ClusterCodec.h>
#include <ff/storage/VertexCodec.h>

#include "PackedVertices.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <random>
#include <vector>

namespace ff::builder {
namespace {

using Point = std::array<float, 3>;

float distance(const Point& a, const Point& b) {
    return std::sqrt(
            (a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

/** The distance from `p` to the nearest of `kept` among `points`. */
float nearestKept(const Point& p, const std::vector<Point>& points, const std::vector<std::uint32_t>& kept) {
    float best = INFINITY;
    for (const std::uint32_t k : kept)
        best = std::min(best, distance(p, points[k]));
    return best;
}

std::vector<std::uint32_t> shuffledOrder(std::size_t n, std::uint32_t seed) {
    std::vector<std::uint32_t> order(n);
    std::iota(order.begin(), order.end(), 0u);
    std::mt19937 rng(seed);
    std::shuffle(order.begin(), order.end(), rng);
    return order;
}

TEST(SplatsTest, StratificationLeavesEveryPointCoveredWithinTheRadius) {
    std::mt19937 rng(1);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    std::vector<Point> points(6000);
    for (Point& p : points)
        p = {unit(rng), 0.02f * unit(rng), unit(rng)}; // a rough sheet
    constexpr float radius = 0.05f;
    const std::vector<std::uint32_t> kept = stratify(points, shuffledOrder(points.size(), 2), radius);
    ASSERT_FALSE(kept.empty());
    for (std::size_t i = 0; i < points.size(); ++i)
        ASSERT_LE(nearestKept(points[i], points, kept), radius) << "point " << i;
    // It thins: a disc of the radius holds ~50 points here; what is left is about one a disc.
    EXPECT_LT(kept.size(), points.size() / 10) << kept.size();
    EXPECT_TRUE(std::is_sorted(kept.begin(), kept.end()));
}

// The cascade the paper warns of (Fig. 5b): points along a line, each within the radius of the
// next, visited in order. Deleting any point with a neighbour left would delete all but the
// last; the rule keeps the last cover of every deleted point.
TEST(SplatsTest, StratificationNeverDeletesTheOnlyCoverOfADeletedPoint) {
    constexpr float radius = 1.0f;
    std::vector<Point> chain;
    for (int i = 0; i < 40; ++i)
        chain.push_back({0.9f * static_cast<float>(i), 0.0f, 0.0f});
    std::vector<std::uint32_t> inOrder(chain.size());
    std::iota(inOrder.begin(), inOrder.end(), 0u);
    const std::vector<std::uint32_t> kept = stratify(chain, inOrder, radius);
    EXPECT_GT(kept.size(), 1u);
    for (std::size_t i = 0; i < chain.size(); ++i)
        EXPECT_LE(nearestKept(chain[i], chain, kept), radius) << "point " << i;
    // Every other point goes: 0 (covered by 1), 1 must stay (0's only cover), 2 goes, ...
    EXPECT_LE(kept.size(), chain.size() / 2 + 1);
}

constexpr int kCells = 48; // a 48 x 48 sheet of unit squares: 4,608 triangles

using testing::upFacingVertex;

/** A flat sheet at height `y`, red where x < 24 and blue beyond. */
std::vector<storage::PackedTriangle> sheet(float y = 0.0f) {
    std::vector<storage::PackedTriangle> out;
    const auto colorAt = [](int x) {
        return x < kCells / 2 ? std::array<std::uint8_t, 4>{200, 20, 20, 255}
                              : std::array<std::uint8_t, 4>{20, 20, 200, 255};
    };
    for (int z = 0; z < kCells; ++z)
        for (int x = 0; x < kCells; ++x) {
            const auto v = [&](int dx, int dz) {
                return upFacingVertex(static_cast<float>(x + dx), y, static_cast<float>(z + dz), colorAt(x));
            };
            out.push_back({{v(0, 0), v(0, 1), v(1, 1)}});
            out.push_back({{v(0, 0), v(1, 1), v(1, 0)}});
        }
    return out;
}

storage::PositionGrid gridFor() {
    return storage::PositionGrid::covering({-1, -1, -1}, {kCells + 1, 2, kCells + 1}, 16).value();
}

TEST(SplatsTest, ASplatSetCoversItsSurfaceWithinThePromisedRadius) {
    const auto source = sheet();
    constexpr float spacing = kCells / 8.0f;
    SplatSet splats;
    ASSERT_EQ(splatSource(source, spacing, 0.25f, gridFor(), 7, splats), SplatOutcome::Kept);
    EXPECT_TRUE(splats.triangles.empty()) << "no triangle of a unit square keeps 3 splats";
    EXPECT_FLOAT_EQ(splats.error, 0.25f + splatCoverRadius(spacing) + std::sqrt(3.0f) * gridFor().maxError());
    EXPECT_LE(static_cast<double>(splats.points.size()), kMaxSplatShare * static_cast<double>(source.size()));
    // Every point of the sheet (a probe grid, corners and edges included) within the radius.
    float worst = 0.0f;
    for (int i = 0; i <= 240; ++i)
        for (int j = 0; j <= 240; ++j) {
            const Point p{kCells * static_cast<float>(i) / 240.0f, 0.0f, kCells * static_cast<float>(j) / 240.0f};
            float nearest = INFINITY;
            for (const storage::PackedVertex& v : splats.points)
                nearest = std::min(nearest, distance(p, v.position));
            worst = std::max(worst, nearest);
        }
    EXPECT_LE(worst, splatCoverRadius(spacing)) << worst;
    std::printf("farthest from a splat: %.3f x the spacing; %zu splats\n", worst / spacing, splats.points.size());
    // And the stratification thins: a cover of discs of spacing/2 (~2.6/spacing² by the paper)
    // in a few hundred points, not the thousands of candidates.
    const double perArea = static_cast<double>(splats.points.size()) * spacing * spacing / (kCells * kCells);
    std::printf("%.2f splats per spacing squared\n", perArea);
    EXPECT_LT(perArea, 4.6) << splats.points.size() << " splats"; // the paper's worst case
}

TEST(SplatsTest, ColoursAreFilteredOverTheirNeighbourhoodOnly) {
    constexpr float spacing = kCells / 8.0f;
    SplatSet splats;
    ASSERT_EQ(splatSource(sheet(), spacing, 0.0f, gridFor(), 3, splats), SplatOutcome::Kept);
    int far = 0;
    for (const storage::PackedVertex& v : splats.points) {
        const float fromEdge = std::abs(v.position[0] - kCells / 2.0f);
        if (fromEdge <= spacing / 2.0f + 0.01f)
            continue; // the Gaussian reaches across the colour edge
        ++far;
        const std::array<std::uint8_t, 4> expected = v.position[0] < kCells / 2.0f
                                                             ? std::array<std::uint8_t, 4>{200, 20, 20, 255}
                                                             : std::array<std::uint8_t, 4>{20, 20, 200, 255};
        for (std::size_t c = 0; c < 4; ++c)
            EXPECT_NEAR(v.color[c], expected[c], 1) << v.position[0];
        EXPECT_GT(storage::decodeOctNormal(v.normalOct)[1], 0.9999f);
    }
    EXPECT_GT(far, 20);
}

// Wires: triangles too thin for draws by area to find (their area fills no bin), covered
// because every edge's points are candidates too.
TEST(SplatsTest, ThinWiresAreCoveredAlongTheirLength) {
    std::vector<storage::PackedTriangle> wires;
    const std::array<std::uint8_t, 4> black{10, 10, 10, 255};
    for (int w = 0; w < 20; ++w)
        for (int k = 0; k < 60; ++k) {
            const float z = 1.0f + 2.3f * static_cast<float>(w);
            const float x0 = 0.8f * static_cast<float>(k);
            const float x1 = x0 + 0.8f;
            wires.push_back({{upFacingVertex(x0, 0.5f, z, black), upFacingVertex(x1, 0.5f, z, black),
                              upFacingVertex(x1, 0.5f, z + 0.001f, black)}});
        }
    constexpr float spacing = kCells / 8.0f;
    SplatSet splats;
    ASSERT_EQ(splatSource(wires, spacing, 0.0f, gridFor(), 13, splats), SplatOutcome::Kept);
    float worst = 0.0f;
    for (const storage::PackedTriangle& t : wires)
        for (int i = 0; i <= 8; ++i) {
            const float at = static_cast<float>(i) / 8.0f;
            const Point p{t.vertices[0].position[0] + at * (t.vertices[1].position[0] - t.vertices[0].position[0]),
                          0.5f, t.vertices[0].position[2]};
            float nearest = INFINITY;
            for (const storage::PackedVertex& v : splats.points)
                nearest = std::min(nearest, distance(p, v.position));
            worst = std::max(worst, nearest);
        }
    EXPECT_LE(worst, splatCoverRadius(spacing)) << worst << " from a splat, " << splats.points.size() << " splats";
}

// KHR_materials_unlit survives splatting: an unlit surface's splats are unlit, with its colours.
TEST(SplatsTest, AnUnlitSurfaceGivesUnlitSplats) {
    auto source = sheet();
    for (storage::PackedTriangle& t : source)
        for (storage::PackedVertex& v : t.vertices)
            v.normalOct = storage::kUnlitNormalOct;
    SplatSet splats;
    ASSERT_EQ(splatSource(source, kCells / 8.0f, 0.0f, gridFor(), 9, splats), SplatOutcome::Kept);
    ASSERT_FALSE(splats.points.empty());
    for (const storage::PackedVertex& v : splats.points)
        EXPECT_TRUE(storage::isUnlitNormal(v.normalOct));
}

// The paper's rule: a triangle that would keep more than a few splats is cheaper drawn as it
// is. Two triangles as large as the sheet above a fine sheet: they stay triangles, the fine
// sheet is splatted.
TEST(SplatsTest, LargeTrianglesAreKeptAsTriangles) {
    auto source = sheet();
    const std::array<std::uint8_t, 4> grey{128, 128, 128, 255};
    const auto big = [&](float x, float z) { return upFacingVertex(x, 1.0f, z, grey); };
    source.push_back({{big(0, 0), big(0, kCells), big(kCells, kCells)}});
    source.push_back({{big(0, 0), big(kCells, kCells), big(kCells, 0)}});
    constexpr float spacing = kCells / 8.0f;
    SplatSet splats;
    ASSERT_EQ(splatSource(source, spacing, 0.0f, gridFor(), 5, splats), SplatOutcome::Kept);
    ASSERT_EQ(splats.triangles.size(), 2u);
    EXPECT_EQ(splats.triangles[0].vertices[0].color, grey);
    for (const storage::PackedVertex& v : splats.points)
        EXPECT_LT(v.position[1], 0.5f) << "a splat of a kept triangle";
    EXPECT_GT(splats.points.size(), 50u);
}

TEST(SplatsTest, TheSameSeedGivesTheSameSplatsAndASmallSourceDoesNotPay) {
    constexpr float spacing = kCells / 8.0f;
    SplatSet a;
    SplatSet b;
    ASSERT_EQ(splatSource(sheet(), spacing, 0.0f, gridFor(), 11, a), SplatOutcome::Kept);
    ASSERT_EQ(splatSource(sheet(), spacing, 0.0f, gridFor(), 11, b), SplatOutcome::Kept);
    ASSERT_EQ(a.points.size(), b.points.size());
    for (std::size_t i = 0; i < a.points.size(); ++i) {
        EXPECT_EQ(a.points[i].position, b.points[i].position);
        EXPECT_EQ(a.points[i].color, b.points[i].color);
    }
    // 32 triangles cannot be replaced by fewer than 0.6 x 32 splats at a fine spacing.
    const auto all = sheet();
    SplatSet few;
    EXPECT_EQ(
            splatSource(std::span(all).first(32), 0.5f, 0.0f, gridFor(), 1, few), SplatOutcome::NotReducing);
    EXPECT_EQ(splatSource({}, spacing, 0.0f, gridFor(), 1, few), SplatOutcome::Empty);
}

} // namespace
} // namespace ff::builder
