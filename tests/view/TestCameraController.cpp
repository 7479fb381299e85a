#include "CameraController.h"
#include "ViewerControls.h"

#include <gtest/gtest.h>

#include <cmath>

namespace ff::viewer {
namespace {

const runtime::Bounds kBounds{{-1.0f, 0.0f, -2.0f}, {3.0f, 2.0f, 2.0f}};
constexpr float kFov = 0.7853982f;

void expectNear(const glm::vec3& a, const glm::vec3& b, float tolerance = 1e-4f) {
    EXPECT_NEAR(a.x, b.x, tolerance);
    EXPECT_NEAR(a.y, b.y, tolerance);
    EXPECT_NEAR(a.z, b.z, tolerance);
}

CameraController orbitController(float azimuth = 30.0f, float elevation = 20.0f) {
    return CameraController(
            runtime::Camera::orbit(kBounds, 3.0f, azimuth, elevation, kFov),
            kBounds.center(),
            kBounds);
}

TEST(CameraControllerTest, StartsAtTheInitialCameraExactly) {
    const runtime::Camera initial = runtime::Camera::orbit(kBounds, 3.0f, 30.0f, 20.0f, kFov);
    const CameraController controller(initial, kBounds.center(), kBounds);
    const runtime::Camera camera = controller.camera();
    EXPECT_EQ(camera.eye, initial.eye);
    EXPECT_EQ(camera.forward, initial.forward);
    EXPECT_EQ(camera.up, initial.up);
    EXPECT_EQ(controller.mode(), NavigationMode::Orbit);
}

TEST(CameraControllerTest, OrbitMatchesCameraOrbitAtTheNewAngles) {
    CameraController controller = orbitController();
    controller.orbit(20.0f, -5.0f);
    const runtime::Camera expected = runtime::Camera::orbit(kBounds, 3.0f, 50.0f, 15.0f, kFov);
    expectNear(controller.camera().eye, expected.eye);
    expectNear(controller.camera().forward, expected.forward);
    expectNear(controller.camera().up, expected.up);
}

TEST(CameraControllerTest, ElevationStopsShortOfThePoles) {
    CameraController controller = orbitController();
    controller.orbit(0.0f, 500.0f);
    EXPECT_LT(controller.camera().forward.y, -0.99f);
    EXPECT_GT(controller.camera().forward.y, -1.0f);
}

TEST(CameraControllerTest, ZoomScalesTheDistanceToThePivot) {
    CameraController controller = orbitController();
    const float before = glm::length(controller.camera().eye - kBounds.center());
    controller.zoom(0.5f);
    EXPECT_NEAR(glm::length(controller.camera().eye - kBounds.center()), 0.5f * before, 1e-4f);
    InputState scroll;
    scroll.scroll = 1.0;
    controller.update(scroll, 0.016, 480);
    EXPECT_LT(glm::length(controller.camera().eye - kBounds.center()), 0.5f * before);
}

TEST(CameraControllerTest, LeftDragOrbitsInOrbitModeOnly) {
    CameraController controller = orbitController();
    InputState drag;
    drag.leftDrag = {100.0, 0.0};
    const glm::vec3 start = controller.camera().eye;
    controller.update(drag, 0.016, 480);
    EXPECT_GT(glm::length(controller.camera().eye - start), 1e-3f);
    EXPECT_NEAR(
            glm::length(controller.camera().eye - kBounds.center()),
            glm::length(start - kBounds.center()),
            1e-4f);

    controller.toggleMode();
    const glm::vec3 flyStart = controller.camera().eye;
    controller.update(drag, 0.016, 480);
    EXPECT_EQ(controller.camera().eye, flyStart);
}

TEST(CameraControllerTest, FlyMovesAtHalfTheSceneRadiusPerSecondAndFasterWithShift) {
    CameraController controller = orbitController();
    controller.toggleMode();
    ASSERT_EQ(controller.mode(), NavigationMode::Fly);
    const runtime::Camera start = controller.camera();
    InputState forward;
    forward.down[static_cast<std::size_t>(Key::W)] = true;
    controller.update(forward, 1.0, 480);
    expectNear(controller.camera().eye, start.eye + start.forward * (0.5f * kBounds.radius()));

    forward.down[static_cast<std::size_t>(Key::Shift)] = true;
    const glm::vec3 before = controller.camera().eye;
    controller.update(forward, 1.0, 480);
    EXPECT_NEAR(glm::length(controller.camera().eye - before), 2.5f * kBounds.radius(), 1e-3f);
}

TEST(CameraControllerTest, RightDragLooksAroundWithoutMoving) {
    CameraController controller = orbitController();
    controller.toggleMode();
    const runtime::Camera start = controller.camera();
    InputState look;
    look.rightDrag = {50.0, 20.0};
    controller.update(look, 0.016, 480);
    EXPECT_EQ(controller.camera().eye, start.eye);
    EXPECT_LT(glm::dot(controller.camera().forward, start.forward), 0.999f);
    EXPECT_NEAR(glm::length(controller.camera().forward), 1.0f, 1e-5f);
}

TEST(CameraControllerTest, ResetReturnsToTheInitialViewInOrbitMode) {
    CameraController controller = orbitController();
    const runtime::Camera initial = controller.camera();
    controller.orbit(45.0f, 10.0f);
    controller.toggleMode();
    InputState move;
    move.down[static_cast<std::size_t>(Key::D)] = true;
    controller.update(move, 0.5, 480);
    controller.reset();
    EXPECT_EQ(controller.mode(), NavigationMode::Orbit);
    EXPECT_EQ(controller.camera().eye, initial.eye);
    EXPECT_EQ(controller.camera().forward, initial.forward);
}

TEST(CameraControllerTest, ClipPlanesAreRefittedToTheScene) {
    CameraController controller = orbitController();
    controller.zoom(10.0f);
    const runtime::Camera camera = controller.camera();
    const float distance = glm::length(camera.eye - kBounds.center());
    EXPECT_LT(camera.zNear, distance - kBounds.radius() + 1e-3f);
    EXPECT_GT(camera.zFar, distance + 0.5f * kBounds.radius());
    EXPECT_LE(camera.zFar, 1.01f * (distance + kBounds.radius()) + 1e-3f);
}

TEST(ViewerControlsTest, EpsilonHalvesToZeroAndDoublesBack) {
    ViewerControls controls;
    controls.halveEpsilon();
    EXPECT_FLOAT_EQ(controls.epsilonPixels, 0.5f);
    for (int i = 0; i < 10; ++i)
        controls.halveEpsilon();
    EXPECT_EQ(controls.epsilonPixels, 0.0f);
    controls.doubleEpsilon();
    EXPECT_FLOAT_EQ(controls.epsilonPixels, ViewerControls::kMinEpsilon);
}

TEST(ViewerControlsTest, BudgetKeysChangeTheCacheBudgetOnceThereIsOne) {
    ViewerControls controls;
    controls.gpuBudgetBytes = 64ull << 20;
    controls.halveBudget();
    EXPECT_EQ(controls.gpuBudgetBytes, 32ull << 20);
    controls.cacheBudgetBytes = 1ull << 30;
    controls.doubleBudget();
    EXPECT_EQ(controls.cacheBudgetBytes, 2ull << 30);
    EXPECT_EQ(controls.gpuBudgetBytes, 32ull << 20);
    for (int i = 0; i < 40; ++i)
        controls.halveBudget();
    EXPECT_EQ(controls.cacheBudgetBytes, ViewerControls::kMinBudgetBytes);
}

TEST(ViewerControlsTest, MethodToggles) {
    ViewerControls controls;
    controls.toggleMethod();
    EXPECT_EQ(controls.method, runtime::Method::Full);
    controls.toggleMethod();
    EXPECT_EQ(controls.method, runtime::Method::Hierarchical);
}

} // namespace
} // namespace ff::viewer
