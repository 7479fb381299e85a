// World sizes of local boxes under affine transforms (the ε rule's measures), checked against
// computations that share nothing with src/: the silhouette as the convex hull of the eight
// world corners projected onto the plane across the view direction, and the nearest distance
// as the minimum over a dense grid of the box's points.

#include <ff/runtime/TransformMetric.h>

#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace ff::runtime {
namespace {

/** Area of the convex hull of 2-D points (Andrew's monotone chain, then the shoelace sum). */
double hullArea(std::vector<glm::dvec2> points) {
    std::sort(points.begin(), points.end(), [](const glm::dvec2& a, const glm::dvec2& b) {
        return a.x != b.x ? a.x < b.x : a.y < b.y;
    });
    auto cross = [](const glm::dvec2& o, const glm::dvec2& a, const glm::dvec2& b) {
        return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
    };
    std::vector<glm::dvec2> hull(2 * points.size());
    std::size_t k = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
        while (k >= 2 && cross(hull[k - 2], hull[k - 1], points[i]) <= 0)
            --k;
        hull[k++] = points[i];
    }
    for (std::size_t i = points.size() - 1, lower = k + 1; i > 0; --i) {
        while (k >= lower && cross(hull[k - 2], hull[k - 1], points[i - 1]) <= 0)
            --k;
        hull[k++] = points[i - 1];
    }
    double area = 0.0;
    for (std::size_t i = 0; i + 1 < k; ++i)
        area += hull[i].x * hull[i + 1].y - hull[i + 1].x * hull[i].y;
    return 0.5 * std::fabs(area);
}

/** The silhouette of the world parallelepiped seen along the world direction centre -> eye. */
double silhouetteArea(
        const glm::mat4& single,
        const glm::vec3& lo,
        const glm::vec3& hi,
        const glm::vec3& localEye) {
    const glm::dmat4 m(
            single); // in double: a 0.004 thick slab's corners would lose digits in float
    const glm::dvec3 eye(m * glm::dvec4(localEye, 1.0));
    const glm::dvec3 centre(m * glm::dvec4(glm::dvec3(0.5f * (lo + hi)), 1.0));
    const glm::dvec3 d = glm::normalize(eye - centre);
    const glm::dvec3 helper = std::fabs(d.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
    const glm::dvec3 u = glm::normalize(glm::cross(d, helper));
    const glm::dvec3 v = glm::cross(d, u);
    std::vector<glm::dvec2> projected;
    for (int i = 0; i < 8; ++i) {
        const glm::vec3 corner((i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z);
        const glm::dvec3 world(m * glm::dvec4(corner, 1.0));
        projected.emplace_back(glm::dot(world, u), glm::dot(world, v));
    }
    return hullArea(projected);
}

/** Minimum world distance over a (steps+1)³ grid of the box's points. */
double gridNearest(
        const glm::mat4& m,
        const glm::vec3& lo,
        const glm::vec3& hi,
        const glm::vec3& localEye,
        int steps) {
    const glm::dvec3 eye(m * glm::vec4(localEye, 1.0f));
    double best = INFINITY;
    for (int i = 0; i <= steps; ++i)
        for (int j = 0; j <= steps; ++j)
            for (int k = 0; k <= steps; ++k) {
                const glm::vec3 t(
                        static_cast<float>(i) / static_cast<float>(steps),
                        static_cast<float>(j) / static_cast<float>(steps),
                        static_cast<float>(k) / static_cast<float>(steps));
                const glm::dvec3 world(m * glm::vec4(lo + t * (hi - lo), 1.0f));
                best = std::min(best, glm::length(world - eye));
            }
    return best;
}

struct Case {
    const char* name;
    glm::mat4 transform;
};

std::vector<Case> cases() {
    glm::mat4 sheared(1.0f);
    sheared[1] = glm::vec4(0.8f, 1.0f, 0.0f, 0.0f);
    sheared[2] = glm::vec4(-0.5f, 0.3f, 2.0f, 0.0f);
    const glm::mat4 turn = glm::rotate(glm::mat4(1.0f), 0.7f, glm::normalize(glm::vec3(1, 2, 3)));
    return {
            {"identity", glm::mat4(1.0f)},
            {"uniform scale and turn",
             glm::translate(glm::mat4(1.0f), {1, 2, 3}) * turn *
                     glm::scale(glm::mat4(1.0f), glm::vec3(3.0f))},
            {"slab (10, 0.004, 1)", glm::scale(glm::mat4(1.0f), {10.0f, 0.004f, 1.0f})},
            {"turned slab", turn * glm::scale(glm::mat4(1.0f), {0.004f, 10.0f, 1.0f})},
            {"mirrored", glm::scale(glm::mat4(1.0f), {-2.0f, 0.5f, 1.0f})},
            {"sheared", sheared},
            {"sheared and turned",
             turn * sheared * glm::scale(glm::mat4(1.0f), {4.0f, 0.1f, 1.0f})},
    };
}

TEST(TransformMetricTest, ProjectedAreaIsTheWorldSilhouette) {
    std::mt19937 random(7);
    std::uniform_real_distribution<float> coordinate(-3.0f, 3.0f);
    for (const Case& c : cases()) {
        SCOPED_TRACE(c.name);
        const TransformMetric metric(c.transform);
        for (int trial = 0; trial < 50; ++trial) {
            const glm::vec3 lo(coordinate(random), coordinate(random), coordinate(random));
            const glm::vec3 hi = lo + glm::vec3(
                                              0.1f + std::fabs(coordinate(random)),
                                              0.2f,
                                              0.1f + std::fabs(coordinate(random)));
            const glm::vec3 eye(
                    coordinate(random) * 4.0f,
                    coordinate(random) * 4.0f,
                    coordinate(random) * 4.0f);
            const double expected = silhouetteArea(c.transform, lo, hi, eye);
            EXPECT_NEAR(metric.projectedArea(lo, hi, eye), expected, 1e-4 * expected + 1e-7);
        }
    }
}

TEST(TransformMetricTest, NearestDistanceIsTheWorldMinimumOverTheBox) {
    std::mt19937 random(11);
    std::uniform_real_distribution<float> coordinate(-3.0f, 3.0f);
    constexpr int kSteps = 60;
    for (const Case& c : cases()) {
        SCOPED_TRACE(c.name);
        const TransformMetric metric(c.transform);
        // The grid's points are at most half a diagonal step from the true nearest point.
        for (int trial = 0; trial < 12; ++trial) {
            const glm::vec3 lo(coordinate(random), coordinate(random), coordinate(random));
            const glm::vec3 hi = lo + glm::vec3(0.5f, 1.0f, 1.5f);
            const glm::vec3 eye(
                    coordinate(random) * 3.0f,
                    coordinate(random) * 3.0f,
                    coordinate(random) * 3.0f);
            const double grid = gridNearest(c.transform, lo, hi, eye, kSteps);
            const glm::vec3 step = (hi - lo) / static_cast<float>(kSteps);
            const double slack = 0.5 * glm::length(glm::mat3(c.transform) * step) + 1e-5;
            const float nearest = metric.nearestDistance(lo, hi, eye);
            EXPECT_LE(nearest, grid + 1e-4 * grid + 1e-6);
            EXPECT_GE(nearest, grid - slack);
        }
    }
}

TEST(TransformMetricTest, AnEyeInsideTheBoxIsAtDistanceZero) {
    for (const Case& c : cases()) {
        SCOPED_TRACE(c.name);
        EXPECT_EQ(
                TransformMetric(c.transform)
                        .nearestDistance(
                                glm::vec3(-1.0f), glm::vec3(1.0f), glm::vec3(0.2f, -0.3f, 0.9f)),
                0.0f);
    }
}

// The slab of issue 13 (a unit box scaled (10, 0.004, 1)): from above it covers its 10 x 1
// face, edge-on its 10 x 0.004 side; never the x scale squared times the local area (100).
TEST(TransformMetricTest, ASlabFaceOnCoversItsWorldFace) {
    const TransformMetric metric(glm::scale(glm::mat4(1.0f), {10.0f, 0.004f, 1.0f}));
    const glm::vec3 eye(0.0f, 0.0f, 100.0f); // along z: the slab's 10 x 0.004 edge
    EXPECT_NEAR(
            metric.projectedArea(glm::vec3(-0.5f), glm::vec3(0.5f), eye), 10.0f * 0.004f, 1e-6f);
    const glm::vec3 above(0.0f, 100.0f / 0.004f, 0.0f); // 100 world units above: the 10 x 1 face
    EXPECT_NEAR(metric.projectedArea(glm::vec3(-0.5f), glm::vec3(0.5f), above), 10.0f, 1e-4f);
    EXPECT_NEAR(
            metric.nearestDistance(glm::vec3(-0.5f), glm::vec3(0.5f), above),
            100.0f - 0.002f,
            1e-3f);
}

} // namespace
} // namespace ff::runtime
