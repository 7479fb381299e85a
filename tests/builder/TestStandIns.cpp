// Stand-ins (builder/src/StandIns.h, StandInError.h): a simplified copy of a source keeps its
// border, halves it at least, and its error covers both where its surface moved and where its
// shading did.

#include "StandIns.h"
#include "StandInError.h"

#include <ff/storage/ClusterCodec.h>
#include <ff/storage/VertexCodec.h>

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <set>
#include <vector>

namespace ff::builder {
namespace {

constexpr int kCells = 48; // a 48 x 48 grid of unit squares: 4,608 triangles

storage::PackedVertex vertexAt(int x, int z, float height, std::array<std::uint8_t, 4> color) {
    storage::PackedVertex v;
    v.position = {static_cast<float>(x), height, static_cast<float>(z)};
    v.normalOct = storage::encodeOctNormal(0.0f, 1.0f, 0.0f);
    v.color = color;
    return v;
}

/** A flat square sheet; `colorAt(x, z)` colours its vertices. */
template <typename Color>
std::vector<storage::PackedTriangle> sheet(Color colorAt) {
    std::vector<storage::PackedTriangle> out;
    for (int z = 0; z < kCells; ++z)
        for (int x = 0; x < kCells; ++x) {
            const auto v = [&](int dx, int dz) { return vertexAt(x + dx, z + dz, 0.0f, colorAt(x + dx, z + dz)); };
            out.push_back({{v(0, 0), v(0, 1), v(1, 1)}});
            out.push_back({{v(0, 0), v(1, 1), v(1, 0)}});
        }
    return out;
}

/** The sheet of one colour, its height a wave, so simplification stops at its target rather
 *  than at its ring. */
std::vector<storage::PackedTriangle> wavySheet() {
    std::vector<storage::PackedTriangle> out =
            sheet([](int, int) { return std::array<std::uint8_t, 4>{90, 120, 60, 255}; });
    for (storage::PackedTriangle& t : out)
        for (storage::PackedVertex& v : t.vertices)
            v.position[1] = 0.5f * std::sin(0.7f * v.position[0]) * std::cos(0.9f * v.position[2]);
    return out;
}

storage::PositionGrid gridFor() {
    return storage::PositionGrid::covering({0, -1, 0}, {kCells, 1, kCells}, 16).value();
}

std::set<std::array<std::uint32_t, 3>> borderCorners(
        const std::vector<storage::PackedTriangle>& triangles, const storage::PositionGrid& grid) {
    // On the grid: a stand-in's corners are the grid's positions of the source's.
    const std::uint32_t lo = grid.quantize({0, 0, 0})[0];
    const std::uint32_t hi = grid.quantize({kCells, 0, kCells})[0];
    std::set<std::array<std::uint32_t, 3>> out;
    for (const storage::PackedTriangle& t : triangles)
        for (const storage::PackedVertex& v : t.vertices) {
            const std::array<std::uint32_t, 3> q = grid.quantize(v.position);
            if (q[0] == lo || q[0] == hi || q[2] == lo || q[2] == hi)
                out.insert(q);
        }
    return out;
}

TEST(StandInTest, AFlatSheetOfOneColourSimplifiesWithoutErrorAndKeepsItsBorder) {
    const storage::PositionGrid grid = gridFor();
    const auto source = sheet([](int, int) { return std::array<std::uint8_t, 4>{90, 120, 60, 255}; });
    const std::optional<StandIn> standIn = simplifySource({source, 0.25f, true, 0.0f}, grid);
    ASSERT_TRUE(standIn.has_value());
    EXPECT_LE(standIn->triangles.size(), source.size() * 6 / 10);
    EXPECT_FLOAT_EQ(standIn->error, 0.25f) << "flat and alike: only the error it was given";
    // The border's vertices all stay (a neighbour drawn at another level meets them).
    EXPECT_EQ(borderCorners(standIn->triangles, grid), borderCorners(source, grid));
}

TEST(StandInTest, SurfaceErrorsAddUpTheTreeAndShadingErrorsDoNot) {
    // A flat sheet of one colour moves nothing and shades alike: its surface error is the one
    // it was given, and its shading error the largest below it, not that plus its own.
    const storage::PositionGrid grid = gridFor();
    const auto source = sheet([](int, int) { return std::array<std::uint8_t, 4>{90, 120, 60, 255}; });
    const std::optional<StandIn> standIn = simplifySource({source, 0.25f, true, 5.0f}, grid);
    ASSERT_TRUE(standIn.has_value());
    EXPECT_FLOAT_EQ(standIn->surfaceError, 0.25f);
    EXPECT_FLOAT_EQ(standIn->shadingError, 5.0f);
    EXPECT_FLOAT_EQ(standIn->error, 5.0f) << "the larger of the two";
}

TEST(StandInTest, AStandInAimsAtAShareOfItsSourceOnTopOfItsRing) {
    // A wavy sheet, so simplification stops at its target rather than at its ring: a share of
    // its triangles, plus the ring of triangles along the locked border (one a border cell,
    // two at two of the corners), which the lock keeps.
    const storage::PositionGrid grid = gridFor();
    std::vector<storage::PackedTriangle> source = wavySheet();
    const std::optional<StandIn> standIn = simplifySource({source, 0.0f, true, 0.0f}, grid);
    ASSERT_TRUE(standIn.has_value());
    const double whole = static_cast<double>(source.size());
    const double ring = 4.0 * kCells - 2.0;
    EXPECT_NEAR(static_cast<double>(standIn->triangles.size()), kStandInTargetShare * whole + ring, 0.01 * whole);
    EXPECT_EQ(borderCorners(standIn->triangles, grid), borderCorners(source, grid));
}

TEST(StandInTest, AStandInWhoseRingIsLargeAimsAtTheMostItMayKeep) {
    // The wavy sheet beside 1,521 loose quads (a tree's leaves: every edge open, so all in the
    // ring, which the lock keeps): its ring on top of the share is over the 0.6 a stand-in may
    // keep, so it aims at 0.6 instead — and reaches it on the sheet's interior, where aiming at
    // ring plus share would have come back over 0.6 and kept no stand-in at all.
    const storage::PositionGrid grid = gridFor();
    std::vector<storage::PackedTriangle> source = wavySheet();
    constexpr int kLeavesPerSide = 39;
    const std::array<std::uint8_t, 4> green{40, 140, 40, 255};
    for (int i = 0; i < kLeavesPerSide; ++i)
        for (int j = 0; j < kLeavesPerSide; ++j) {
            const float x = 0.2f + 1.2f * static_cast<float>(i);
            const float z = 0.2f + 1.2f * static_cast<float>(j);
            const auto corner = [&](float dx, float dz) {
                storage::PackedVertex v = vertexAt(0, 0, 0.9f, green);
                v.position = {x + dx, 0.9f, z + dz};
                return v;
            };
            source.push_back({{corner(0, 0), corner(0, 0.4f), corner(0.4f, 0.4f)}});
            source.push_back({{corner(0, 0), corner(0.4f, 0.4f), corner(0.4f, 0)}});
        }
    const double whole = static_cast<double>(source.size());
    const double ring = 4.0 * kCells - 2.0 + 2.0 * kLeavesPerSide * kLeavesPerSide;
    ASSERT_GT(ring + kStandInTargetShare * whole, kMaxStandInShare * whole) << "the case this is about";
    const std::optional<StandIn> standIn = simplifySource({source, 0.0f, true, 0.0f}, grid);
    ASSERT_TRUE(standIn.has_value());
    EXPECT_LE(static_cast<double>(standIn->triangles.size()), kMaxStandInShare * whole);
    EXPECT_GE(static_cast<double>(standIn->triangles.size()), ring);
}

TEST(StandInTest, AColourEdgeAcrossAFlatSheetCountsAsError) {
    // Flat, so meshoptimizer's error is 0; the colour steps from green to white at x = 24.5.
    const storage::PositionGrid grid = gridFor();
    const auto source = sheet([](int x, int) {
        return x <= kCells / 2 ? std::array<std::uint8_t, 4>{40, 160, 40, 255}
                               : std::array<std::uint8_t, 4>{250, 250, 250, 255};
    });
    const std::optional<StandIn> standIn = simplifySource({source, 0.0f, true, 0.0f}, grid);
    ASSERT_TRUE(standIn.has_value());
    // A removed vertex beside the edge takes a colour from across it, a unit or more away.
    EXPECT_GE(standIn->error, 1.0f);
    EXPECT_LT(standIn->error, static_cast<float>(kCells));
}

TEST(StandInTest, TheLimitsDropStandInsTooLargeForAPageAndLeavesBelowTheTop) {
    // One node holding the sheet: the root of a prototype (a stand-in of its own), or a chunk's
    // root below it (a leaf: none), or with a stand-in larger than the limit allows (none).
    const storage::PositionGrid grid = gridFor();
    const auto triangles = sheet([](int, int) { return std::array<std::uint8_t, 4>{90, 120, 60, 255}; });
    std::vector<BuildNode> nodes(1);
    nodes[0].kind = static_cast<std::uint8_t>(storage::NodeKind::Cell);
    nodes[0].triangleCount = triangles.size();
    nodes[0].boundsMin = {0.0f, 0.0f, 0.0f};
    nodes[0].boundsMax = {kCells, 0.0f, kCells};
    const auto build = [&](const StandInLimits& limits, StandInCounts& counts) {
        return buildStandIns(nodes, triangles, grid, {}, 1, nullptr, counts, limits).value();
    };
    StandInCounts top;
    EXPECT_TRUE(build({}, top)[0].has_value());
    EXPECT_EQ(top.kept, 1u);
    StandInCounts chunkRoot;
    EXPECT_FALSE(build({std::numeric_limits<std::size_t>::max(), false}, chunkRoot)[0].has_value());
    EXPECT_EQ(chunkRoot.tooSmall, 1u);
    StandInCounts capped;
    EXPECT_FALSE(build({16, true}, capped)[0].has_value());
    EXPECT_EQ(capped.tooLarge, 1u);
    // About eight pages at ~10 bytes a stand-in triangle.
    EXPECT_EQ(maxStandInTriangles(4096), 8u * storage::pagePayloadBytes(4096) / 10u);
}

TEST(StandInTest, ShadingDifferenceWeighsColourAndNormalSteps) {
    const storage::PackedVertex a = vertexAt(0, 0, 0.0f, {100, 100, 100, 255});
    storage::PackedVertex b = a;
    EXPECT_EQ(shadingDifference(a, b), 0.0f);
    b.color = {116, 100, 100, 255}; // half a colour step
    EXPECT_NEAR(shadingDifference(a, b), 16.0f / kShadingColourStep, 1e-6f);
    b.color = a.color;
    const float turned = kShadingNormalStepDegrees * 3.14159265f / 180.0f;
    b.normalOct = storage::encodeOctNormal(std::sin(turned), std::cos(turned), 0.0f);
    EXPECT_NEAR(shadingDifference(a, b), 1.0f, 0.02f);
    b.normalOct = storage::kUnlitNormalOct;
    EXPECT_EQ(shadingDifference(a, b), 1.0f) << "lit against unlit";
}

} // namespace
} // namespace ff::builder
