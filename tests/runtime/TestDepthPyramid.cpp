// The depth pyramid of `--occlusion-backend hzb` (runtime/src/DepthPyramid.h): levels that
// cover every pixel (odd sizes included), and a box test that never hides what may show.

#include "DepthPyramid.h"
#include "OcclusionBoxes.h"

#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include <vector>

namespace ff::runtime {
namespace {

TEST(DepthPyramidTest, OddSizesKeepTheirLastRowAndColumn) {
    // 5 x 3, all near but the last column's middle texel, which is far: a pyramid that rounded
    // down (2 x 1, then 1 x 1) would lose that column and call a box over it hidden.
    constexpr int kWidth = 5;
    constexpr int kHeight = 3;
    std::vector<float> depth(kWidth * kHeight, 0.2f);
    depth[1 * kWidth + 4] = 0.9f;
    DepthPyramid pyramid;
    pyramid.build(kWidth, kHeight, depth);
    ASSERT_EQ(pyramid.levels(), 4); // 5x3, 3x2, 2x1, 1x1
    EXPECT_FLOAT_EQ(pyramid.at(1, 2, 0), 0.9f);
    EXPECT_FLOAT_EQ(pyramid.at(pyramid.levels() - 1, 0, 0), 0.9f);
    EXPECT_TRUE(pyramid.mayPass(4, 1, 4, 1, 0.5f));
    EXPECT_TRUE(pyramid.mayPass(0, 0, 4, 2, 0.5f)) << "the whole image holds a far texel";
    EXPECT_FALSE(pyramid.mayPass(0, 0, 3, 2, 0.5f)) << "the first four columns are all near";
}

TEST(DepthPyramidTest, EveryLevelIsTheFarthestOfWhatItCovers) {
    constexpr int kWidth = 37;
    constexpr int kHeight = 23;
    std::vector<float> depth(kWidth * kHeight);
    for (int i = 0; i < kWidth * kHeight; ++i)
        depth[static_cast<std::size_t>(i)] = static_cast<float>((i * 7919) % 1000) / 1000.0f;
    DepthPyramid pyramid;
    pyramid.build(kWidth, kHeight, depth);
    for (int level = 1; level < pyramid.levels(); ++level) {
        const int size = 1 << level;
        for (int y = 0; y * size < kHeight; ++y)
            for (int x = 0; x * size < kWidth; ++x) {
                float farthest = 0.0f;
                for (int py = y * size; py < std::min(kHeight, (y + 1) * size); ++py)
                    for (int px = x * size; px < std::min(kWidth, (x + 1) * size); ++px)
                        farthest = std::max(
                                farthest, depth[static_cast<std::size_t>(py * kWidth + px)]);
                ASSERT_FLOAT_EQ(pyramid.at(level, x, y), farthest)
                        << "level " << level << " texel " << x << "," << y;
            }
    }
}

TEST(DepthPyramidTest, ACoarseTexelReachingPastTheOccluderDoesNotKeepABoxVisible) {
    // Near everywhere but the top row. The rectangle stops 7 rows short of it, but the 16-pixel
    // texels of the level it is first read at reach it: their quarters inside decide.
    constexpr int kWidth = 64;
    constexpr int kHeight = 48;
    std::vector<float> depth(kWidth * kHeight, 0.2f);
    for (int x = 0; x < kWidth; ++x)
        depth[static_cast<std::size_t>((kHeight - 1) * kWidth + x)] = 1.0f;
    DepthPyramid pyramid;
    pyramid.build(kWidth, kHeight, depth);
    EXPECT_FALSE(pyramid.mayPass(10, 5, 50, 40, 0.5f));
    EXPECT_TRUE(pyramid.mayPass(10, 5, 50, kHeight - 1, 0.5f)) << "reaches the far row";
    EXPECT_TRUE(pyramid.mayPass(10, 5, 50, 40, 0.1f)) << "in front of the near surface";
}

/** A 64 x 48 view down -z with a wall of depth `wall` over the pixels [x0, x1) x all. */
struct WallView {
    glm::mat4 viewProjection =
            glm::perspective(0.8f, 64.0f / 48.0f, 1.0f, 100.0f) *
            glm::lookAt(glm::vec3(0.0f, 0.0f, 10.0f), glm::vec3(0.0f), glm::vec3(0.0f, 1.0f, 0.0f));
    DepthPyramid pyramid;
    float depthAt(const glm::vec3& p) const {
        const glm::vec4 clip = viewProjection * glm::vec4(p, 1.0f);
        return clip.z / clip.w * 0.5f + 0.5f;
    }
    void build(int x0, int x1, float wall) {
        std::vector<float> depth(64 * 48, 1.0f);
        for (int y = 0; y < 48; ++y)
            for (int x = x0; x < x1; ++x)
                depth[static_cast<std::size_t>(y * 64 + x)] = wall;
        pyramid.build(64, 48, depth);
    }
};

using test::boxAround;

TEST(DepthPyramidTest, ABoxBehindAWallIsHiddenAndOneBesideItIsNot) {
    WallView view;
    view.build(0, 64, view.depthAt(glm::vec3(0.0f, 0.0f, 2.0f))); // a wall across the view at z = 2
    EXPECT_FALSE(boxMayBeVisible(
            view.pyramid, boxAround({0, 0, -3}, 0.5f), view.viewProjection, 64, 48));
    EXPECT_TRUE(
            boxMayBeVisible(view.pyramid, boxAround({0, 0, 4}, 0.5f), view.viewProjection, 64, 48))
            << "in front of the wall";
    // The wall only over the left half: a box whose rectangle reaches the right half shows.
    view.build(0, 32, view.depthAt(glm::vec3(0.0f, 0.0f, 2.0f)));
    EXPECT_FALSE(boxMayBeVisible(
            view.pyramid, boxAround({-2, 0, -3}, 0.5f), view.viewProjection, 64, 48));
    EXPECT_TRUE(boxMayBeVisible(
            view.pyramid, boxAround({0.2f, 0, -3}, 0.5f), view.viewProjection, 64, 48));
    // A box reaching behind the camera cannot be bounded on screen: visible.
    EXPECT_TRUE(boxMayBeVisible(
            view.pyramid, boxAround({0, 0, 10}, 1.0f), view.viewProjection, 64, 48));
}

TEST(DepthPyramidTest, AnEmptyPyramidHidesNothing) {
    DepthPyramid pyramid;
    EXPECT_TRUE(pyramid.mayPass(0, 0, 10, 10, 0.0f));
}

} // namespace
} // namespace ff::runtime
