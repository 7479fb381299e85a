// The grid a prototype's clusters get: a step of its sampled median edge / 1024, from a bounded,
// deterministic sample; fallbacks where there is nothing to measure or too much extent.

#include <ff/builder/GridChoice.h>

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace ff::builder {
namespace {

/** A right triangle with legs `leg` at `x`: edges leg, leg and leg·√2. */
storage::PackedTriangle triangle(float x, float leg) {
    storage::PackedTriangle t{};
    t.vertices[0].position = {x, 0.0f, 0.0f};
    t.vertices[1].position = {x + leg, 0.0f, 0.0f};
    t.vertices[2].position = {x, leg, 0.0f};
    return t;
}

TEST(GridChoiceTest, TheStepIsTheMedianEdgeOverAThousandAndTwentyFour) {
    std::vector<storage::PackedTriangle> triangles;
    for (int i = 0; i < 1000; ++i)
        triangles.push_back(triangle(static_cast<float>(i), 2.0f)); // median edge 2
    EdgeSampler edges;
    edges.add(triangles);
    EXPECT_EQ(edges.median(), 2.0f);
    const auto grid = chooseGrid({0, 0, 0}, {1002, 2, 0}, edges);
    ASSERT_TRUE(grid.isOk()) << grid.status().toString();
    EXPECT_NEAR(grid->step, 2.0f / kGridStepsPerMedianEdge, 1e-9f);
    EXPECT_EQ(grid->bits, 19); // 1002 / (2 / 1024) = 513 k steps
    EXPECT_LE(grid->maxError(), 2.0f / kGridStepsPerMedianEdge);
}

TEST(GridChoiceTest, TheSampleIsBoundedDeterministicAndFollowsTheDistribution) {
    // A million edges, a tenth of the triangles long: the sample stays at its capacity and its
    // median is the short legs' (60 % of the edges are 1, 30 % √2), the same on every run.
    std::vector<storage::PackedTriangle> triangles;
    for (int i = 0; i < 333'334; ++i)
        triangles.push_back(triangle(0.0f, i % 10 == 0 ? 50.0f : 1.0f));
    EdgeSampler a;
    EdgeSampler b;
    for (std::size_t at = 0; at < triangles.size(); at += 1000) {
        const std::span<const storage::PackedTriangle> batch(
                triangles.data() + at, std::min<std::size_t>(1000, triangles.size() - at));
        a.add(batch);
        b.add(batch);
    }
    EXPECT_EQ(a.edgesSeen(), 3u * triangles.size());
    EXPECT_EQ(a.sampleSize(), EdgeSampler::kCapacity);
    EXPECT_EQ(a.median(), b.median());
    EXPECT_EQ(a.median(), 1.0f);
}

TEST(GridChoiceTest, FallsBackWhereThereIsNothingToMeasureOrTooMuchExtent) {
    EdgeSampler none;
    const auto empty = chooseGrid({0, 0, 0}, {10, 10, 10}, none);
    ASSERT_TRUE(empty.isOk());
    EXPECT_EQ(empty->bits, storage::kDefaultPositionGridBits);

    // Tiny triangles in a vast prototype: a step of 1e-6 over 1e6 units would need 2^40 steps.
    EdgeSampler tiny;
    const std::vector<storage::PackedTriangle> t = {triangle(0.0f, 1e-3f)};
    tiny.add(t);
    const auto vast = chooseGrid({0, 0, 0}, {1e6f, 1, 1}, tiny);
    ASSERT_TRUE(vast.isOk()) << vast.status().toString();
    EXPECT_EQ(vast->bits, storage::kMaxPositionGridBits);

    // Non-finite edges are not sampled; non-finite bounds are an error.
    storage::PackedTriangle nan = triangle(0.0f, 1.0f);
    nan.vertices[1].position[0] = NAN;
    EdgeSampler withNan;
    withNan.add(std::span(&nan, 1));
    EXPECT_EQ(withNan.edgesSeen(), 1u); // only the edge between vertices 2 and 0
    EXPECT_FALSE(chooseGrid({0, 0, 0}, {INFINITY, 1, 1}, withNan).isOk());
}

} // namespace
} // namespace ff::builder
