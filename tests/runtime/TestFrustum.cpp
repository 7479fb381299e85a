// The frustum test of instances in their local frame: the planes of P V M, tested against the
// local box. For any affine M — scaled per axis, mirrored or sheared — a plane pulled back
// through M is still a plane, so the test must say "outside" exactly when all eight corners,
// carried to clip space by P V M, lie outside one and the same clip plane (checked here corner
// by corner, sharing nothing with src/).

#include <ff/runtime/Frustum.h>

#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include <random>
#include <string>
#include <vector>

namespace ff::runtime {
namespace {

/** True if every corner of the local box violates one clip plane (-w <= x, y, z <= w). */
bool allCornersOutsideOnePlane(
        const glm::mat4& clipFromLocal, const glm::vec3& lo, const glm::vec3& hi) {
    for (int plane = 0; plane < 6; ++plane) {
        const int axis = plane / 2;
        const float sign = plane % 2 == 0 ? 1.0f : -1.0f;
        bool allOutside = true;
        for (int i = 0; i < 8 && allOutside; ++i) {
            const glm::vec3 corner(
                    (i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z);
            const glm::vec4 clip = clipFromLocal * glm::vec4(corner, 1.0f);
            allOutside =
                    clip.w + sign * clip[axis] < 0.0f; // outside w + x >= 0, or w - x >= 0, ...
        }
        if (allOutside)
            return true;
    }
    return false;
}

TEST(FrustumTest, LocalFrameTestMatchesTheCornersForMirroredShearedAndScaledInstances) {
    const glm::mat4 viewProjection =
            glm::perspective(glm::radians(45.0f), 4.0f / 3.0f, 0.5f, 200.0f) *
            glm::lookAt(glm::vec3(0, 3, 25), glm::vec3(0), glm::vec3(0, 1, 0));
    glm::mat4 sheared(1.0f);
    sheared[2] = glm::vec4(0.7f, -0.4f, 1.0f, 0.0f);
    const std::vector<std::pair<std::string, glm::mat4>> transforms = {
            {"identity", glm::mat4(1.0f)},
            {"slab (10, 0.004, 1)", glm::scale(glm::mat4(1.0f), {10.0f, 0.004f, 1.0f})},
            {"mirrored", glm::scale(glm::mat4(1.0f), {-3.0f, 1.0f, 2.0f})},
            {"sheared", glm::translate(glm::mat4(1.0f), {2, 0, 0}) * sheared},
            {"mirrored, sheared, turned",
             glm::rotate(glm::mat4(1.0f), 0.8f, glm::vec3(1, 1, 0)) * sheared *
                     glm::scale(glm::mat4(1.0f), {1.0f, -1.0f, 0.5f})},
    };
    std::mt19937 random(5);
    std::uniform_real_distribution<float> coordinate(-30.0f, 30.0f);
    std::uniform_real_distribution<float> size(0.1f, 6.0f);
    for (const auto& [name, transform] : transforms) {
        SCOPED_TRACE(name);
        const glm::mat4 clipFromLocal = viewProjection * transform;
        const Frustum frustum(clipFromLocal);
        int inside = 0;
        int outside = 0;
        for (int trial = 0; trial < 2000; ++trial) {
            const glm::vec3 lo(coordinate(random), coordinate(random), coordinate(random));
            const glm::vec3 hi = lo + glm::vec3(size(random), size(random), size(random));
            const bool culled = allCornersOutsideOnePlane(clipFromLocal, lo, hi);
            ASSERT_EQ(frustum.intersects(lo, hi), !culled) << "trial " << trial;
            ++(culled ? outside : inside);
        }
        EXPECT_GT(inside, 50);
        EXPECT_GT(outside, 50);
    }
}

} // namespace
} // namespace ff::runtime
