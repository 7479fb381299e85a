#include <ff/runtime/CameraPath.h>
#include <ff/runtime/CameraPathGenerators.h>
#include <ff/runtime/PathCuts.h>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

// Expected values are derived by hand in the comments, not from src/.

namespace ff::runtime {
namespace {

constexpr double kPi = std::numbers::pi;

glm::dquat aboutY(double degrees) {
    return glm::angleAxis(glm::radians(degrees), glm::dvec3(0, 1, 0));
}

CameraKeyframe
key(double time, glm::dvec3 position, glm::dquat orientation = {1, 0, 0, 0}, double fov = 45.0) {
    CameraKeyframe k;
    k.time = time;
    k.position = position;
    k.orientation = orientation;
    k.fovDegrees = fov;
    return k;
}

/** Same rotation: q and -q are equal rotations. */
void expectSameRotation(const glm::dquat& a, const glm::dquat& b, double tolerance = 1e-12) {
    EXPECT_NEAR(std::fabs(glm::dot(a, b)), 1.0, tolerance);
}

void expectNear(const glm::dvec3& a, const glm::dvec3& b, double tolerance) {
    EXPECT_NEAR(a.x, b.x, tolerance);
    EXPECT_NEAR(a.y, b.y, tolerance);
    EXPECT_NEAR(a.z, b.z, tolerance);
}

/** A spline path with uneven spacing in time and in space, turning in every direction. */
CameraPath makeUnevenSpline() {
    std::vector<CameraKeyframe> keys = {
            key(0.0, {0, 0, 0}, aboutY(0), 40),
            key(0.7, {1, 0.5, -0.2}, aboutY(30), 50),
            key(2.0, {1.5, 2, -3}, glm::angleAxis(0.8, glm::normalize(glm::dvec3(1, 1, 0))), 35),
            key(2.4, {6, 2.2, -3.5}, aboutY(-70), 60),
            key(4.0, {7, 0, 1}, aboutY(-150), 45),
    };
    auto path = CameraPath::create(keys, PathInterpolation::Spline);
    EXPECT_TRUE(path) << path.status().toString();
    return std::move(path).value();
}

// ---- JSON ------------------------------------------------------------------------------------

TEST(CameraPathTest, JsonRoundTripIsLossless) {
    std::vector<CameraKeyframe> keys = {
            key(0.1, {1.0 / 3.0, -2e-7, 12345.678}, aboutY(10), 33.3),
            key(1.25, {4, 5, 6}, glm::angleAxis(2.0, glm::normalize(glm::dvec3(1, 2, 3))), 90),
    };
    keys[1].name = "a \"quoted\" name";
    for (const FrameSampling sampling : {FrameSampling::rate(24.0), FrameSampling::frames(7)}) {
        for (const PathInterpolation mode :
             {PathInterpolation::Linear, PathInterpolation::Spline}) {
            auto path = CameraPath::create(keys, mode, sampling);
            ASSERT_TRUE(path) << path.status().toString();
            const std::string text = path->toJson();
            auto parsed = CameraPath::fromJson(text);
            ASSERT_TRUE(parsed) << parsed.status().toString() << "\n" << text;
            EXPECT_EQ(parsed->interpolation(), mode);
            EXPECT_EQ(parsed->sampling().count, sampling.count);
            EXPECT_EQ(parsed->frameCount(), path->frameCount());
            ASSERT_EQ(parsed->keyframes().size(), keys.size());
            for (std::size_t i = 0; i < keys.size(); ++i) {
                const CameraKeyframe& a = path->keyframes()[i];
                const CameraKeyframe& b = parsed->keyframes()[i];
                EXPECT_EQ(a.time, b.time);
                EXPECT_EQ(a.position, b.position);
                EXPECT_EQ(a.orientation, b.orientation);
                EXPECT_EQ(a.fovDegrees, b.fovDegrees);
                EXPECT_EQ(a.name, b.name);
            }
            EXPECT_EQ(parsed->toJson(), text);
        }
    }
}

TEST(CameraPathTest, ParsesTargetForwardAndDefaults) {
    // Keyframe 0 looks from (0,0,5) at the origin: forward -Z, up +Y, the identity orientation.
    // Keyframe 1 looks along +X with up +Y: a quarter turn clockwise about Y (seen from above).
    const char* text = R"({
        "interpolation": "spline", "fov": 60,
        "keyframes": [
            {"time": 0, "position": [0, 0, 5], "target": [0, 0, 0]},
            {"time": 2, "position": [1, 0, 5], "forward": [3, 0, 0], "up": [0, 2, 0], "fov": 30},
            {"time": 3, "position": [2, 0, 5], "orientation": [0, 0, 0, 1]}
        ]})";
    auto path = CameraPath::fromJson(text);
    ASSERT_TRUE(path) << path.status().toString();
    EXPECT_EQ(path->interpolation(), PathInterpolation::Spline);
    EXPECT_EQ(path->sampling().count, 0);
    EXPECT_EQ(path->sampling().fps, 30.0); // default
    EXPECT_EQ(path->frameCount(), 91);     // 3 s at 30 fps, both ends
    const auto& k = path->keyframes();
    expectSameRotation(k[0].orientation, glm::dquat(1, 0, 0, 0));
    expectSameRotation(k[1].orientation, aboutY(-90));
    EXPECT_EQ(k[0].fovDegrees, 60.0);
    EXPECT_EQ(k[1].fovDegrees, 30.0);
    EXPECT_EQ(k[2].fovDegrees, 60.0);
}

struct BadJson {
    ErrorCode code;
    const char* message; ///< expected substring
};

TEST(CameraPathTest, BadJsonNamesTheKey) {
    const std::string ok0 = R"({"time": 0, "position": [0,0,0], "target": [0,0,-1]})";
    const std::string ok1 = R"({"time": 1, "position": [1,0,0], "target": [0,0,-1]})";
    const auto frames = [](const std::string& keyframes, const std::string& extra = "") {
        return "{" + extra + "\"keyframes\": [" + keyframes + "]}";
    };
    const std::vector<std::pair<std::string, BadJson>> cases = {
            {"{\"keyframes\": [", {ErrorCode::InvalidInput, "not valid JSON"}},
            {"[1, 2]", {ErrorCode::InvalidInput, "expected a JSON object"}},
            {"{}", {ErrorCode::InvalidInput, "missing key \"keyframes\""}},
            {frames(""), {ErrorCode::InvalidInput, "keyframes: needs at least 1 keyframe"}},
            {frames(ok0 + ", 5"), {ErrorCode::InvalidInput, "keyframes[1]: expected an object"}},
            {frames(ok0 + R"(, {"time": 1, "target": [0,0,0]})"),
             {ErrorCode::InvalidInput, "keyframes[1]: missing key \"position\""}},
            {frames(R"({"position": [0,0,0], "target": [1,0,0]})"),
             {ErrorCode::InvalidInput, "keyframes[0]: missing key \"time\""}},
            {frames(R"({"time": "0", "position": [0,0,0], "target": [1,0,0]})"),
             {ErrorCode::InvalidInput, "keyframes[0].time: expected a number, got string"}},
            {frames(R"({"time": 0, "position": [0,1e999,0], "target": [1,0,0]})"),
             {ErrorCode::InvalidInput,
              "not valid JSON: [json.exception.out_of_range.406] number overflow parsing '1e999'"}},
            {frames(R"({"time": 0, "position": [0,0], "target": [1,0,0]})"),
             {ErrorCode::InvalidInput, "keyframes[0].position: expected an array of 3 numbers"}},
            {frames(ok0 + "," + ok1 + "," + ok1),
             {ErrorCode::InvalidInput, "keyframes[2].time: 1 is not after keyframes[1].time (1)"}},
            {frames(ok1 + "," + ok0),
             {ErrorCode::InvalidInput, "keyframes[1].time: 0 is not after keyframes[0].time (1)"}},
            {frames(ok0, R"("interpolation": "cubic", )"),
             {ErrorCode::InvalidInput, "interpolation: unknown value \"cubic\""}},
            {frames(R"({"time": 0, "position": [0,0,0]})"),
             {ErrorCode::InvalidInput,
              "keyframes[0]: missing key \"target\", \"orientation\" or \"forward\""}},
            {frames(R"({"time": 0, "position": [0,0,0], "target": [1,0,0], "forward": [1,0,0]})"),
             {ErrorCode::InvalidInput, "keyframes[0]: give only one of"}},
            {frames(R"({"time": 0, "position": [0,0,0], "orientation": [0,0,0,0.5]})"),
             {ErrorCode::InvalidInput,
              "keyframes[0].orientation: not a unit quaternion (length 0.5)"}},
            {frames(R"({"time": 0, "position": [0,0,0], "orientation": [0,0,0,1], "up": [0,1,0]})"),
             {ErrorCode::InvalidInput, "keyframes[0].up: only goes with"}},
            {frames(R"({"time": 0, "position": [1,2,3], "target": [1,2,3]})"),
             {ErrorCode::InvalidInput, "keyframes[0].target: equals the position"}},
            {frames(R"({"time": 0, "position": [0,0,0], "forward": [0,0,0]})"),
             {ErrorCode::InvalidInput, "keyframes[0].forward: zero vector"}},
            {frames(ok0 + R"(, {"time": 1, "position": [0,0,0], "target": [1,0,0], "fov": 180})"),
             {ErrorCode::InvalidInput, "keyframes[1].fov: must be in (0, 180) degrees"}},
            {frames(R"({"time": 0, "postion": [0,0,0], "target": [1,0,0]})"),
             {ErrorCode::InvalidInput, "keyframes[0].postion: unknown key"}},
            {frames(ok0, R"("speed": 3, )"), {ErrorCode::InvalidInput, "speed: unknown key"}},
            {frames(ok0, R"("fps": -1, )"), {ErrorCode::InvalidInput, "fps: must be positive"}},
            {frames(ok0, R"("frames": 0, )"),
             {ErrorCode::InvalidInput, "frames: expected an integer"}},
            {frames(ok0, R"("frames": 2.5, )"),
             {ErrorCode::InvalidInput, "frames: expected an integer"}},
            {frames(ok0, R"("frames": 2, "fps": 3, )"),
             {ErrorCode::InvalidInput, "frames: give \"fps\" or"}},
            {frames(ok0, R"("format": "other", )"), {ErrorCode::InvalidInput, "format: expected"}},
            {frames(ok0, R"("version": 2, )"),
             {ErrorCode::Unsupported, "version 2 is not supported"}},
    };
    for (const auto& [text, expected] : cases) {
        auto path = CameraPath::fromJson(text);
        ASSERT_FALSE(path) << text;
        EXPECT_EQ(path.status().code(), expected.code) << text << "\n" << path.status().toString();
        EXPECT_NE(path.status().message().find(expected.message), std::string::npos)
                << "input: " << text << "\nexpected: " << expected.message
                << "\ngot: " << path.status().toString();
    }
}

TEST(CameraPathTest, CreateRejectsBadKeyframes) {
    EXPECT_EQ(
            CameraPath::create({}, PathInterpolation::Linear).status().code(),
            ErrorCode::InvalidArgument);
    auto nan = CameraPath::create({key(0, {0, std::nan(""), 0})}, PathInterpolation::Linear);
    ASSERT_FALSE(nan);
    EXPECT_NE(nan.status().message().find("keyframes[0].position"), std::string::npos);
    auto huge = CameraPath::create({key(0, {1e300, 0, 0})}, PathInterpolation::Linear);
    ASSERT_FALSE(huge);
    EXPECT_NE(huge.status().message().find("beyond the range of float"), std::string::npos);
    auto badFps = CameraPath::create(
            {key(0, {0, 0, 0})}, PathInterpolation::Linear, FrameSampling::rate(0));
    EXPECT_FALSE(badFps);
}

// ---- interpolation ---------------------------------------------------------------------------

TEST(CameraPathTest, LinearInterpolatesMidpointsByHand) {
    // t in [1, 3]; at t = 2 (u = 1/2) and t = 1.5 (u = 1/4). Orientation 0 -> 90 degrees about Y,
    // so at u the camera is turned 90u degrees: forward = Ry(a) (0,0,-1) = (-sin a, 0, -cos a).
    auto path = CameraPath::create(
            {key(1, {0, 0, 0}, aboutY(0), 30), key(3, {2, 4, -6}, aboutY(90), 60)},
            PathInterpolation::Linear);
    ASSERT_TRUE(path);
    const CameraPose mid = path->pose(2.0);
    expectNear(mid.position, {1, 2, -3}, 1e-15);
    EXPECT_NEAR(mid.fovDegrees, 45.0, 1e-13);
    const double a = kPi / 4;
    expectNear(mid.forward(), {-std::sin(a), 0, -std::cos(a)}, 1e-12);
    expectNear(mid.up(), {0, 1, 0}, 1e-12);

    const CameraPose quarter = path->pose(1.5);
    expectNear(quarter.position, {0.5, 1, -1.5}, 1e-15);
    EXPECT_NEAR(quarter.fovDegrees, 37.5, 1e-13);
    const double b = kPi / 8;
    expectNear(quarter.forward(), {-std::sin(b), 0, -std::cos(b)}, 1e-12);

    const Camera camera = path->sample(2.0);
    EXPECT_NEAR(camera.eye.y, 2.0f, 1e-6f);
    EXPECT_NEAR(camera.fovY, glm::radians(45.0f), 1e-6f);
    EXPECT_NEAR(glm::dot(camera.forward, camera.up), 0.0f, 1e-6f);
}

TEST(CameraPathTest, LinearTakesTheShorterArc) {
    // q and -q are the same rotation: 0 -> 90 degrees given as the negated quaternion still turns
    // 45 degrees at the midpoint, not 135 the long way round.
    auto path = CameraPath::create(
            {key(0, {0, 0, 0}, aboutY(0)), key(1, {0, 0, 0}, -aboutY(90))},
            PathInterpolation::Linear);
    ASSERT_TRUE(path);
    expectSameRotation(path->pose(0.5).orientation, aboutY(45));
}

TEST(CameraPathTest, SplinePassesThroughKeyframesExactly) {
    const CameraPath path = makeUnevenSpline();
    for (const CameraKeyframe& k : path.keyframes()) {
        const CameraPose p = path.pose(k.time);
        expectNear(p.position, k.position, 1e-12);
        EXPECT_NEAR(p.fovDegrees, k.fovDegrees, 1e-12);
        expectSameRotation(p.orientation, k.orientation);
    }
}

/** Largest difference between the one-sided derivatives at `t` (second-order formulas). */
double derivativeJump(const CameraPath& path, double t, double h) {
    const auto p = [&path](double time) { return path.pose(time).position; };
    const glm::dvec3 left = (3.0 * p(t) - 4.0 * p(t - h) + p(t - 2 * h)) / (2 * h);
    const glm::dvec3 right = (-3.0 * p(t) + 4.0 * p(t + h) - p(t + 2 * h)) / (2 * h);
    return glm::length(left - right) / std::max(1.0, glm::length(left));
}

TEST(CameraPathTest, SplineIsC1SmoothInTime) {
    const CameraPath path = makeUnevenSpline();
    const auto& keys = path.keyframes();
    constexpr double kH = 1e-5;
    for (std::size_t i = 1; i + 1 < keys.size(); ++i)
        EXPECT_LT(derivativeJump(path, keys[i].time, kH), 1e-6) << "at keyframe " << i;
    // Inside the segments too (a smooth cubic; this also catches a wrong segment lookup).
    for (double t = 0.05; t < 3.95; t += 0.173)
        EXPECT_LT(derivativeJump(path, t, kH), 1e-6) << "at t=" << t;

    // The test can see a kink: the linear path through the same keyframes has one.
    auto linear = CameraPath::create(keys, PathInterpolation::Linear);
    ASSERT_TRUE(linear);
    EXPECT_GT(derivativeJump(*linear, keys[1].time, kH), 0.1);
}

TEST(CameraPathTest, SplineHoldsStillBetweenEqualPositions) {
    // Keyframes 1 and 2 share a position: the camera must stay there in between (no overshoot).
    auto path = CameraPath::create(
            {key(0, {0, 0, 0}), key(1, {4, 0, 0}), key(2, {4, 0, 0}), key(3, {4, 4, 0})},
            PathInterpolation::Spline);
    ASSERT_TRUE(path);
    for (double t = 1.0; t <= 2.0; t += 0.05)
        expectNear(path->pose(t).position, {4, 0, 0}, 1e-6);
    // Centripetal knots and the monotone time map keep the first segment on its chord's side:
    // x never runs backwards.
    double x = -1.0;
    for (double t = 0.0; t <= 1.0; t += 0.01) {
        const double next = path->pose(t).position.x;
        EXPECT_GE(next, x - 1e-12) << "t=" << t;
        x = next;
    }
}

TEST(CameraPathTest, OrientationsStayUnitAndHitKeyframes) {
    const CameraPath spline = makeUnevenSpline();
    auto linear = CameraPath::create(spline.keyframes(), PathInterpolation::Linear);
    ASSERT_TRUE(linear);
    for (const CameraPath* path : {&spline, static_cast<const CameraPath*>(&*linear)}) {
        for (double t = -0.5; t <= 4.5; t += 0.01) {
            const CameraPose p = path->pose(t);
            EXPECT_NEAR(glm::length(p.orientation), 1.0, 1e-12) << "t=" << t;
            EXPECT_NEAR(glm::dot(p.forward(), p.up()), 0.0, 1e-12);
        }
        for (const CameraKeyframe& k : path->keyframes())
            expectSameRotation(path->pose(k.time).orientation, k.orientation);
    }
    // Squad is continuous: small steps in time make small turns.
    double largest = 0.0;
    for (double t = 0.0; t < 4.0; t += 1e-3)
        largest = std::max(
                largest,
                1.0 - std::fabs(glm::dot(
                              spline.pose(t).orientation, spline.pose(t + 1e-3).orientation)));
    EXPECT_LT(largest, 1e-4);
}

TEST(CameraPathTest, SamplingClampsToTheTimeRange) {
    const CameraPath path = makeUnevenSpline();
    const auto& keys = path.keyframes();
    expectNear(path.pose(-10.0).position, keys.front().position, 0.0);
    expectNear(
            path.pose(std::numeric_limits<double>::quiet_NaN()).position,
            keys.front().position,
            0.0);
    expectNear(path.pose(99.0).position, keys.back().position, 0.0);
    expectNear(
            path.pose(std::numeric_limits<double>::infinity()).position, keys.back().position, 0.0);
    EXPECT_EQ(path.sample(-1.0).eye, glm::vec3(keys.front().position));

    auto single =
            CameraPath::create({key(5, {1, 2, 3}, aboutY(20), 70)}, PathInterpolation::Spline);
    ASSERT_TRUE(single);
    expectNear(single->pose(0).position, {1, 2, 3}, 0.0);
    EXPECT_EQ(single->frameCount(), 1);
    EXPECT_EQ(single->frameTime(0), 5.0);
}

TEST(CameraPathTest, FrameTimesFollowTheRateOrTheCount) {
    auto byRate = CameraPath::create(
            {key(1, {0, 0, 0}), key(3, {1, 0, 0})},
            PathInterpolation::Linear,
            FrameSampling::rate(30));
    ASSERT_TRUE(byRate);
    EXPECT_EQ(byRate->frameCount(), 61); // 2 s at 30 fps, both ends
    EXPECT_EQ(byRate->frameTime(0), 1.0);
    EXPECT_DOUBLE_EQ(byRate->frameTime(15), 1.5);
    EXPECT_DOUBLE_EQ(byRate->frameTime(60), 3.0);

    auto byCount = CameraPath::create(
            {key(1, {0, 0, 0}), key(3, {1, 0, 0})},
            PathInterpolation::Linear,
            FrameSampling::frames(5));
    ASSERT_TRUE(byCount);
    EXPECT_EQ(byCount->frameCount(), 5);
    const double expected[] = {1.0, 1.5, 2.0, 2.5, 3.0};
    for (std::int64_t i = 0; i < 5; ++i)
        EXPECT_DOUBLE_EQ(byCount->frameTime(i), expected[i]);
}

TEST(CameraPathTest, LookOrientationMapsForwardAndUp) {
    const glm::dquat q = lookOrientation({1, 0, 0}, {0, 5, 0});
    expectNear(q * glm::dvec3(0, 0, -1), {1, 0, 0}, 1e-15);
    expectNear(q * glm::dvec3(0, 1, 0), {0, 1, 0}, 1e-15);
    // Straight down with +Y as the hint: some perpendicular up, still a rotation.
    const glm::dquat down = lookOrientation({0, -2, 0}, {0, 1, 0});
    expectNear(down * glm::dvec3(0, 0, -1), {0, -1, 0}, 1e-15);
    EXPECT_NEAR(glm::length(down), 1.0, 1e-15);
}

// ---- generators ------------------------------------------------------------------------------

const Bounds kBounds{{-10.0f, 0.0f, -4.0f}, {30.0f, 12.0f, 20.0f}};

bool finite(const CameraPose& p) {
    return std::isfinite(p.position.x) && std::isfinite(p.position.y) &&
           std::isfinite(p.position.z) && std::isfinite(p.orientation.w) &&
           std::isfinite(p.orientation.x) && std::isfinite(p.orientation.y) &&
           std::isfinite(p.orientation.z) && std::isfinite(p.fovDegrees);
}

bool inside(const glm::dvec3& p, const Bounds& b) {
    return p.x > b.min.x && p.x < b.max.x && p.y > b.min.y && p.y < b.max.y && p.z > b.min.z &&
           p.z < b.max.z;
}

TEST(CameraPathGeneratorsTest, OrbitKeepsItsDistanceAndLooksAtTheCentre) {
    PathGeneratorOptions options;
    options.frames = 90;
    options.fovDegrees = 50;
    auto path = makeOrbitPath(kBounds, options);
    ASSERT_TRUE(path) << path.status().toString();
    ASSERT_EQ(path->frameCount(), 90);
    const glm::dvec3 centre(kBounds.center());
    const double distance = 2.5 * static_cast<double>(kBounds.radius());
    double turned = 0.0;
    glm::dvec3 previous = path->pose(0).position - centre;
    for (std::int64_t f = 0; f < path->frameCount(); ++f) {
        const CameraPose p = path->pose(path->frameTime(f));
        ASSERT_TRUE(finite(p));
        EXPECT_NEAR(glm::length(p.position - centre), distance, 1e-5 * distance);
        EXPECT_NEAR(glm::dot(p.forward(), glm::normalize(centre - p.position)), 1.0, 1e-9);
        EXPECT_GT(p.position.y, centre.y); // above the horizon
        EXPECT_EQ(p.fovDegrees, 50.0);
        const glm::dvec3 offset = p.position - centre;
        turned += std::atan2(
                glm::cross(previous, offset).y,
                glm::dot(glm::dvec3(previous.x, 0, previous.z), glm::dvec3(offset.x, 0, offset.z)));
        previous = offset;
    }
    EXPECT_NEAR(std::fabs(turned), 2.0 * kPi * 89.0 / 90.0, 1e-9); // a full circle less one step
    // Between frames the spline stays on the circle to well under 1%.
    for (double t = 0.0; t < path->endTime(); t += 0.0123)
        EXPECT_NEAR(glm::length(path->pose(t).position - centre), distance, 1e-3 * distance);
}

TEST(CameraPathGeneratorsTest, FlythroughTravelsInsideAtAThirdOfTheHeight) {
    PathGeneratorOptions options;
    options.frames = 240;
    const Bounds deep{{0, -30, 0}, {10, 0, 100}}; // deeper than wide: travels along Z
    for (const Bounds& bounds : {kBounds, deep}) {
        const double height = bounds.min.y + (bounds.max.y - bounds.min.y) / 3.0;
        for (std::uint64_t seed : {1ULL, 2ULL, 99ULL}) {
            options.seed = seed;
            auto path = makeFlythroughPath(bounds, options);
            ASSERT_TRUE(path) << path.status().toString();
            ASSERT_EQ(path->frameCount(), 240);
            EXPECT_FALSE(inside(path->pose(path->frameTime(0)).position, bounds)); // enters
            double shortest = INFINITY;
            double longest = 0.0;
            for (std::int64_t f = 0; f < 240; ++f) {
                const CameraPose p = path->pose(path->frameTime(f));
                ASSERT_TRUE(finite(p));
                EXPECT_NEAR(p.position.y, height, 1e-4);
                if (f >= 60) { // inside from a quarter of the path to its end
                    EXPECT_TRUE(inside(p.position, bounds)) << "frame " << f << " seed " << seed;
                }
                if (f + 1 < 240) {
                    const glm::dvec3 step =
                            path->pose(path->frameTime(f + 1)).position - p.position;
                    shortest = std::min(shortest, glm::length(step));
                    longest = std::max(longest, glm::length(step));
                    EXPECT_GT(glm::dot(p.forward(), glm::normalize(step)), 0.95)
                            << "frame " << f; // looks ahead
                }
            }
            EXPECT_LT(longest, 1.02 * shortest); // constant speed
        }
    }
    options.seed = 1;
    auto a = makeFlythroughPath(kBounds, options);
    options.seed = 2;
    auto b = makeFlythroughPath(kBounds, options);
    ASSERT_TRUE(a && b);
    EXPECT_NE(a->toJson(), b->toJson());
}

TEST(CameraPathGeneratorsTest, TeleportsAreDeterministicAndJumpFar) {
    PathGeneratorOptions options;
    options.frames = 103;
    options.teleports = 5;
    options.seed = 7;
    auto path = makeTeleportPath(kBounds, options);
    ASSERT_TRUE(path) << path.status().toString();
    auto again = makeTeleportPath(kBounds, options);
    ASSERT_TRUE(again);
    EXPECT_EQ(path->toJson(), again->toJson());
    options.seed = 8;
    auto other = makeTeleportPath(kBounds, options);
    ASSERT_TRUE(other);
    EXPECT_NE(path->toJson(), other->toJson());

    ASSERT_EQ(path->frameCount(), 103);
    const double diagonal = 2.0 * static_cast<double>(kBounds.radius());
    // Holds of 103 / 5 = 20 frames, the last one 23: every frame of a hold sees the same view.
    int jumps = 0;
    for (std::int64_t f = 1; f < 103; ++f) {
        const CameraPose before = path->pose(path->frameTime(f - 1));
        const CameraPose now = path->pose(path->frameTime(f));
        ASSERT_TRUE(finite(now));
        const bool jumpFrame = f % 20 == 0 && f < 100;
        if (jumpFrame) {
            ++jumps;
            EXPECT_GT(glm::length(now.position - before.position), 0.3 * diagonal) << "frame " << f;
        } else {
            EXPECT_EQ(now.position, before.position) << "frame " << f;
            EXPECT_EQ(now.orientation, before.orientation) << "frame " << f;
        }
        // Near the bounds: inside the box grown by 10% per side.
        const glm::dvec3 size(kBounds.max - kBounds.min);
        EXPECT_TRUE(glm::all(
                glm::greaterThanEqual(now.position, glm::dvec3(kBounds.min) - 0.1 * size)));
        EXPECT_TRUE(
                glm::all(glm::lessThanEqual(now.position, glm::dvec3(kBounds.max) + 0.1 * size)));
    }
    EXPECT_EQ(jumps, 4);

    options.frames = 9; // 5 holds of 2 frames need 10
    EXPECT_EQ(makeTeleportPath(kBounds, options).status().code(), ErrorCode::InvalidArgument);
}

TEST(CameraPathGeneratorsTest, HandleFlatAndTinyFramesAndRejectBadBounds) {
    const Bounds flat{{0, 0, 0}, {100, 0, 50}}; // a ground plane
    for (std::int64_t frames : {1, 2, 37}) {
        PathGeneratorOptions options;
        options.frames = frames;
        options.teleports = 1;
        for (auto* make : {&makeOrbitPath, &makeFlythroughPath, &makeTeleportPath}) {
            auto path = make(flat, options);
            ASSERT_EQ(path.isOk(), frames >= 2 || make != &makeTeleportPath)
                    << path.status().toString();
            if (!path)
                continue;
            EXPECT_EQ(path->frameCount(), frames);
            for (std::int64_t f = 0; f < frames; ++f)
                EXPECT_TRUE(finite(path->pose(path->frameTime(f))));
        }
    }
    const Bounds empty{{1, 1, 1}, {0, 0, 0}};
    EXPECT_EQ(makeOrbitPath(empty).status().code(), ErrorCode::InvalidArgument);
    const Bounds infinite{{0, 0, 0}, {INFINITY, 1, 1}};
    EXPECT_EQ(makeFlythroughPath(infinite).status().code(), ErrorCode::InvalidArgument);
    PathGeneratorOptions zeroFrames;
    zeroFrames.frames = 0;
    EXPECT_EQ(makeOrbitPath(kBounds, zeroFrames).status().code(), ErrorCode::InvalidArgument);
}

// Cuts are where a path jumps: a teleport path's holds start with one (103 frames, 5 holds of
// 20, the last 23: cuts at 0, 20, 40, 60, 80), an orbit of 60 frames moving a quarter of the
// radius a frame (issue 13's fast orbit) has only the cold start.
std::vector<std::int64_t> cutFrames(const CameraPath& path) {
    const std::vector<bool> cuts = findPathCuts(path, static_cast<double>(kBounds.radius()));
    std::vector<std::int64_t> frames;
    for (std::size_t f = 0; f < cuts.size(); ++f)
        if (cuts[f])
            frames.push_back(static_cast<std::int64_t>(f));
    return frames;
}

TEST(CameraPathGeneratorsTest, WalkKeepsItsSpeedOnEachLegAndJumpsBetweenThem) {
    PathGeneratorOptions options;
    options.frames = 60;
    options.legs = {{{0, 1.7, 40}, {0, 1.7, 0}, {20, 1.7, 0}}, {{-40, 1.7, -10}, {40, 1.7, -10}}};
    options.legLookAhead = 5.0;
    auto path = makeWalkPath(kBounds, options);
    ASSERT_TRUE(path) << path.status().toString();
    ASSERT_EQ(path->frameCount(), 60);
    // 60 and 80 units long: 26 and 34 frames, at the legs' own constant speeds.
    const CameraPose first = path->pose(path->frameTime(0));
    EXPECT_NEAR(glm::length(first.position - glm::dvec3(0, 1.7, 40)), 0.0, 1e-9);
    EXPECT_NEAR(glm::dot(first.forward(), glm::dvec3(0, 0, -1)), 1.0, 1e-9); // down the first leg
    std::vector<double> steps;
    for (std::int64_t f = 1; f < 60; ++f)
        steps.push_back(glm::length(path->pose(path->frameTime(f)).position -
                                    path->pose(path->frameTime(f - 1)).position));
    const double legOne = 60.0 / 25.0;
    const double legTwo = 80.0 / 33.0;
    std::size_t jumps = 0;
    for (std::size_t i = 0; i < steps.size(); ++i) {
        if (steps[i] > 10.0) {
            ++jumps; // from the first leg's end (20, 1.7, 0) to the second's start
            EXPECT_NEAR(steps[i], glm::length(glm::dvec3(-60, 0, -10)), 1e-9);
            continue;
        }
        // At the corner the step cuts across; elsewhere it is the leg's speed.
        const double speed = i < 25 ? legOne : legTwo;
        if (i != 16) { // 16 x 2.4 < 40 < 17 x 2.4: the corner
            EXPECT_NEAR(steps[i], speed, 1e-6) << "step " << i;
        }
    }
    EXPECT_EQ(jumps, 1u);
    const CameraPose last = path->pose(path->endTime());
    EXPECT_NEAR(glm::length(last.position - glm::dvec3(40, 1.7, -10)), 0.0, 1e-9);
    EXPECT_NEAR(glm::dot(last.forward(), glm::dvec3(1, 0, 0)), 1.0, 1e-9);
}

TEST(CameraPathGeneratorsTest, WalkLegsParseRoundTripAndBadWalksAreRefused) {
    auto legs = parseWalkLegs("0,1.7,40 0,1.7,0; -40,1.7,-10 40,1.7,-10.25");
    ASSERT_TRUE(legs) << legs.status().toString();
    ASSERT_EQ(legs->size(), 2u);
    EXPECT_EQ((*legs)[1][1], glm::dvec3(40, 1.7, -10.25));
    auto again = parseWalkLegs(formatWalkLegs(*legs));
    ASSERT_TRUE(again);
    EXPECT_EQ(*again, *legs);
    EXPECT_FALSE(parseWalkLegs("0,1,2 3,4"));
    EXPECT_FALSE(parseWalkLegs("0,1,x"));
    PathGeneratorOptions options;
    options.frames = 10;
    EXPECT_EQ(makeWalkPath(kBounds, options).status().code(), ErrorCode::InvalidArgument); // no legs
    options.legs = {{{0, 0, 0}}};
    EXPECT_EQ(makeWalkPath(kBounds, options).status().code(), ErrorCode::InvalidArgument); // one point
    options.legs = {{{0, 0, 0}, {0, 0, 0}}};
    EXPECT_EQ(makeWalkPath(kBounds, options).status().code(), ErrorCode::InvalidArgument); // no length
    options.legs = {{{0, 0, 0}, {1, 0, 0}}, {{0, 0, 0}, {1, 0, 0}}};
    options.frames = 3;
    EXPECT_EQ(makeWalkPath(kBounds, options).status().code(), ErrorCode::InvalidArgument); // 2 a leg
}

TEST(PathCutsTest, TeleportsCutAtEveryJumpAndOrbitsOnlyAtTheColdStart) {
    PathGeneratorOptions options;
    options.frames = 103;
    options.teleports = 5;
    options.seed = 7;
    auto teleports = makeTeleportPath(kBounds, options);
    ASSERT_TRUE(teleports) << teleports.status().toString();
    EXPECT_EQ(cutFrames(*teleports), (std::vector<std::int64_t>{0, 20, 40, 60, 80}));

    PathGeneratorOptions orbit;
    orbit.frames = 60;
    auto fast = makeOrbitPath(kBounds, orbit);
    ASSERT_TRUE(fast) << fast.status().toString();
    // 2.5 radii around the centre in 60 frames: about 0.26 radii a frame.
    const double step = glm::length(glm::dvec3(fast->sample(fast->frameTime(1)).eye - fast->sample(fast->frameTime(0)).eye));
    EXPECT_GT(step, 0.2 * static_cast<double>(kBounds.radius()));
    EXPECT_EQ(cutFrames(*fast), (std::vector<std::int64_t>{0}));
}

} // namespace
} // namespace ff::runtime
