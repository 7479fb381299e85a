// The choice of a cell's stand-in by measured error (builder/src/StandInChoice.h,
// builder/src/CellViews.h): the six views see coverage and shading, edge-on slivers included; a
// candidate that keeps its promise is kept at its own error, one that moved further than it
// says is kept only at the error it keeps, one that loses the surface or its colours does not
// pay; of two that pay the one that looks more like its source wins, then the smaller error,
// then the cheaper.

#include "CellViews.h"
#include "StandInChoice.h"

#include <ff/storage/VertexCodec.h>

#include "PackedVertices.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <vector>

namespace ff::builder {
namespace {

constexpr int kCells = 32; // a 32 x 32 sheet of unit squares in y = 0, in a 32-unit box

using testing::upFacingVertex;

/** The sheet, moved `dx` along x, grey, or `color`. */
std::vector<storage::PackedTriangle> sheet(float dx = 0.0f, std::array<std::uint8_t, 4> color = {128, 128, 128, 255}) {
    std::vector<storage::PackedTriangle> out;
    for (int z = 0; z < kCells; ++z)
        for (int x = 0; x < kCells; ++x) {
            const auto v = [&](int ox, int oz) {
                return upFacingVertex(static_cast<float>(x + ox) + dx, 0.0f, static_cast<float>(z + oz), color);
            };
            out.push_back({{v(0, 0), v(0, 1), v(1, 1)}});
            out.push_back({{v(0, 0), v(1, 1), v(1, 0)}});
        }
    return out;
}

const glm::vec3 kMin{0.0f, 0.0f, 0.0f};
const glm::vec3 kMax{kCells, 0.0f, kCells};

std::size_t coveredIn(const CellViews& views, int view) {
    std::size_t covered = 0;
    for (const CellViews::Pixel& p : views.view(view))
        covered += p.covered ? 1u : 0u;
    return covered;
}

TEST(CellViewsTest, ASheetFillsTheViewsFacingItAndShowsAsALineEdgeOn) {
    CellViews views(kMin, kMax, 16);
    views.drawTriangles(sheet());
    EXPECT_EQ(coveredIn(views, 2), 256u); // +y: the whole sheet
    EXPECT_EQ(coveredIn(views, 3), 256u);
    // Edge-on (+x, +z), a sheet of no thickness still covers a row of pixels: conservative.
    EXPECT_EQ(coveredIn(views, 0), 16u);
    EXPECT_EQ(coveredIn(views, 4), 16u);
    // Lit from the eye: facing it, the full colour; edge-on, a quarter.
    EXPECT_EQ(views.view(2)[0].shade[0], 128);
    EXPECT_EQ(views.view(0)[0].shade[0], 32);
}

TEST(CellViewsTest, MismatchAllowsAPixelsShiftAndNoMore) {
    CellViews source(kMin, kMax, 16);
    source.drawTriangles(sheet());
    EXPECT_EQ(viewDifference(source, source, 1, 32.0f).mismatch, 0.0);
    const auto shifted = [&](float dx) {
        CellViews views(kMin, kMax, 16);
        views.drawTriangles(sheet(dx));
        return viewDifference(source, views, 1, 32.0f).mismatch;
    };
    EXPECT_EQ(shifted(2.0f), 0.0);  // a pixel (2 units) off: as a stand-in's error may move it
    EXPECT_GT(shifted(6.0f), 0.05); // three pixels off
    CellViews far(kMin, kMax, 16);
    far.drawTriangles(sheet(6.0f));
    EXPECT_EQ(viewDifference(source, far, 3, 32.0f).mismatch, 0.0) << "within a reach of three";
    CellViews recoloured(kMin, kMax, 16);
    recoloured.drawTriangles(sheet(0.0f, {128, 200, 128, 255}));
    EXPECT_GT(viewDifference(source, recoloured, 1, 32.0f).mismatch, 0.5);
    EXPECT_EQ(viewDifference(source, recoloured, 1, 80.0f).mismatch, 0.0);
    CellViews empty(kMin, kMax, 16);
    EXPECT_EQ(viewDifference(empty, empty, 1, 32.0f).mismatch, 0.0);
    EXPECT_EQ(viewDifference(source, empty, 1, 32.0f).mismatch, 1.0);
}

TEST(CellViewsTest, SplatsCoverDiscsOfTheirDiameterAndAtLeastTheirPixel) {
    CellViews views(kMin, kMax, 16); // 2 units a pixel
    const storage::PackedVertex point = upFacingVertex(16.0f, 0.0f, 16.0f, {255, 255, 255, 255});
    views.drawSplats(std::span(&point, 1), 0.1f);
    EXPECT_EQ(coveredIn(views, 2), 1u);
    CellViews wide(kMin, kMax, 16);
    wide.drawSplats(std::span(&point, 1), 8.0f); // a disc 4 pixels across around a pixel corner
    EXPECT_EQ(coveredIn(wide, 2), 12u);
}

TEST(CellViewsTest, GeometryFarOutsideTheBoxIsClippedNotOverflowed) {
    // Finite but far beyond what an int holds once projected: drawn clipped (UBSan checks the
    // casts), and what lies off the raster draws nothing.
    CellViews views(kMin, kMax, 16);
    const std::array<std::uint8_t, 4> white{255, 255, 255, 255};
    const storage::PackedTriangle huge{{upFacingVertex(-1e15f, 0.0f, -1e15f, white), upFacingVertex(1e15f, 0.0f, -1e15f, white),
                                         upFacingVertex(0.0f, 0.0f, 1e15f, white)}};
    const storage::PackedTriangle edgeOnFar{{upFacingVertex(-1e20f, 0.0f, 5.0f, white), upFacingVertex(1e20f, 0.0f, 5.0f, white),
                                              upFacingVertex(0.0f, 0.0f, 5.0f, white)}};
    views.drawTriangles(std::vector{huge, edgeOnFar});
    EXPECT_EQ(coveredIn(views, 2), 256u);
    CellViews points(kMin, kMax, 16);
    const std::vector<storage::PackedVertex> far = {upFacingVertex(1e30f, 0.0f, 1e30f, white), upFacingVertex(-1e9f, 0.0f, 4.0f, white)};
    points.drawSplats(far, 4.0f);
    points.drawSplats(far, NAN);
    points.drawSplats(far, 1e30f);
    // Only the views along x see the second point (x is what they drop); the first is off all.
    for (int v = 2; v < CellViews::kViews; ++v)
        EXPECT_EQ(coveredIn(points, v), 0u) << "view " << v;
    EXPECT_GT(coveredIn(points, 0), 0u);
}

StandIn candidate(std::vector<storage::PackedTriangle> triangles, float error) {
    StandIn s;
    s.triangles = std::move(triangles);
    s.error = error;
    return s;
}

TEST(StandInChoiceTest, ACandidateThatKeepsItsPromiseKeepsItsError) {
    const auto source = sheet();
    StandInMeasure measure(source, kMin, kMax);
    const MeasuredStandIn m = measure.measure(candidate(sheet(), 2.0f));
    EXPECT_TRUE(m.pays);
    EXPECT_EQ(m.raised, 0);
    EXPECT_EQ(m.error, 2.0f);
    EXPECT_EQ(m.mismatch, 0.0);
}

TEST(StandInChoiceTest, ACandidateThatMovedFurtherThanItSaysKeepsOnlyTheErrorItKeeps) {
    const auto source = sheet();
    StandInMeasure measure(source, kMin, kMax);
    // Moved 3 units, claiming 0.5: three pixels off where it would first be drawn.
    const MeasuredStandIn m = measure.measure(candidate(sheet(3.0f), 0.5f));
    EXPECT_TRUE(m.pays);
    EXPECT_GE(m.raised, 1);
    EXPECT_GE(m.error, 2.0f);
    EXPECT_LE(m.mismatch, kMaxStandInMismatch);
}

TEST(StandInChoiceTest, ACandidateThatLosesTheSurfaceOrItsColoursDoesNotPay) {
    const auto source = sheet();
    StandInMeasure measure(source, kMin, kMax);
    EXPECT_FALSE(measure.measure(candidate({}, 0.5f)).pays);
    EXPECT_FALSE(measure.measure(candidate(sheet(0.0f, {30, 30, 30, 255}), 0.5f)).pays);
    // A quarter of the sheet: its outline is more than a pixel off however far away it is
    // drawn from (half of it would pass where the cell spans two pixels).
    std::vector<storage::PackedTriangle> quarter = sheet();
    quarter.resize(quarter.size() / 4);
    EXPECT_FALSE(measure.measure(candidate(quarter, 0.5f)).pays);
    // An error of half the cell: drawn only where the cube nearly is.
    EXPECT_FALSE(measure.measure(candidate(sheet(), 0.6f * kCells)).pays);
}

TEST(StandInChoiceTest, OfTwoThatPayTheOneThatLooksMoreLikeItsSourceWins) {
    const auto source = sheet();
    StandInMeasure measure(source, kMin, kMax);
    // Both pay; the tinted one promises the smaller error but differs by 20 steps everywhere.
    const StandIn exact = candidate(sheet(), 2.0f);
    const StandIn tinted = candidate(sheet(0.0f, {148, 148, 148, 255}), 1.0f);
    const MeasuredStandIn exactMeasured = measure.measure(exact);
    const MeasuredStandIn tintedMeasured = measure.measure(tinted);
    ASSERT_TRUE(exactMeasured.pays && tintedMeasured.pays);
    EXPECT_TRUE(measure.firstIsBetter(exact, exactMeasured, tinted, tintedMeasured));
    EXPECT_FALSE(measure.firstIsBetter(tinted, tintedMeasured, exact, exactMeasured));
    // Alike: the smaller error wins.
    const StandIn nearer = candidate(sheet(), 1.0f);
    const MeasuredStandIn nearerMeasured = measure.measure(nearer);
    EXPECT_TRUE(measure.firstIsBetter(nearer, nearerMeasured, exact, exactMeasured));
}

TEST(StandInChoiceTest, TheSmallerErrorWinsAndTheCheaperOnATie) {
    MeasuredStandIn a;
    a.error = 1.0f;
    a.pays = true;
    MeasuredStandIn b = a;
    b.error = 2.0f;
    EXPECT_TRUE(prefer(a, 1000, b, 10));
    EXPECT_FALSE(prefer(b, 10, a, 1000));
    b.error = 1.1f; // within kStandInErrorTie
    EXPECT_FALSE(prefer(a, 1000, b, 10));
    EXPECT_TRUE(prefer(a, 10, b, 1000));
}

} // namespace
} // namespace ff::builder
