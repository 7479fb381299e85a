#include "CameraController.h"

#include <algorithm>
#include <cmath>

namespace ff::viewer {

namespace {

constexpr float kDegreesPerPixel = 0.3f; // orbit and look sensitivity
constexpr float kZoomPerNotch = 0.85f;   // distance factor per wheel notch
constexpr float kFlySpeedRadii = 0.5f;   // scene radii per second
constexpr float kFastFactor = 5.0f;      // with Shift
constexpr float kMaxElevation = 89.0f;
const glm::vec3 kWorldUp(0.0f, 1.0f, 0.0f);

// Unit direction at `azimuth` degrees about +Y from +Z, `elevation` degrees up (Camera::orbit's).
glm::vec3 direction(float azimuthDegrees, float elevationDegrees) {
    const float a = glm::radians(azimuthDegrees);
    const float e = glm::radians(elevationDegrees);
    return {std::cos(e) * std::sin(a), std::sin(e), std::cos(e) * std::cos(a)};
}

float azimuthOf(const glm::vec3& d) {
    return glm::degrees(std::atan2(d.x, d.z));
}
float elevationOf(const glm::vec3& d) {
    return glm::degrees(std::asin(std::clamp(d.y, -1.0f, 1.0f)));
}

} // namespace

CameraController::CameraController(
        const runtime::Camera& initial, const glm::vec3& pivot, const runtime::Bounds& bounds)
    : mInitial(initial)
    , mInitialPivot(pivot)
    , mBounds(bounds)
    , mRadius(std::max(bounds.radius(), 1e-6f))
    , mCamera(initial)
    , mPivot(pivot) {
    syncOrbitFromCamera();
}

void CameraController::reset() {
    mCamera = mInitial;
    mPivot = mInitialPivot;
    mMode = NavigationMode::Orbit;
    mFlySpeedScale = 1.0f;
    syncOrbitFromCamera();
}

void CameraController::syncOrbitFromCamera() {
    const glm::vec3 offset = mCamera.eye - mPivot;
    mDistance = std::max(glm::length(offset), 1e-3f * mRadius);
    const glm::vec3 d =
            glm::length(offset) > 0.0f ? offset / glm::length(offset) : -mCamera.forward;
    mAzimuth = azimuthOf(d);
    mElevation = std::clamp(elevationOf(d), -kMaxElevation, kMaxElevation);
}

void CameraController::placeOrbitCamera() {
    const float fov = mCamera.fovY;
    const bool orthographic = mCamera.orthographic;
    const float halfHeight = mCamera.orthoHalfHeight;
    mCamera = runtime::Camera::lookAt(
            mPivot + direction(mAzimuth, mElevation) * mDistance, mPivot, kWorldUp, fov);
    mCamera.orthographic = orthographic;
    mCamera.orthoHalfHeight = halfHeight;
}

void CameraController::orbit(float azimuthDegrees, float elevationDegrees) {
    if (mMode != NavigationMode::Orbit)
        return;
    mAzimuth = std::remainder(mAzimuth + azimuthDegrees, 360.0f);
    mElevation = std::clamp(mElevation + elevationDegrees, -kMaxElevation, kMaxElevation);
    placeOrbitCamera();
}

void CameraController::zoom(float factor) {
    if (mMode != NavigationMode::Orbit || !(factor > 0.0f))
        return;
    mDistance = std::clamp(mDistance * factor, 1e-3f * mRadius, 1e3f * mRadius);
    if (mCamera.orthographic)
        mCamera.orthoHalfHeight *= factor;
    placeOrbitCamera();
}

void CameraController::toggleMode() {
    if (mMode == NavigationMode::Orbit) {
        mMode = NavigationMode::Fly; // keeps the camera where it is
        return;
    }
    // Orbit about the point straight ahead at the last orbit distance.
    mMode = NavigationMode::Orbit;
    mPivot = mCamera.eye + mCamera.forward * mDistance;
    syncOrbitFromCamera();
    placeOrbitCamera();
}

void CameraController::update(const InputState& input, double seconds, int viewportHeight) {
    if (mMode == NavigationMode::Orbit) {
        if (input.leftDrag != glm::dvec2(0.0))
            orbit(-static_cast<float>(input.leftDrag.x) * kDegreesPerPixel,
                  static_cast<float>(input.leftDrag.y) * kDegreesPerPixel);
        if (input.middleDrag != glm::dvec2(0.0)) {
            // Pan so that the point under the cursor at the pivot's depth follows the cursor.
            const glm::vec3 right = glm::normalize(glm::cross(mCamera.forward, mCamera.up));
            const float worldPerPixel = 2.0f * mDistance * std::tan(0.5f * mCamera.fovY) /
                                        static_cast<float>(std::max(viewportHeight, 1));
            mPivot += (-static_cast<float>(input.middleDrag.x) * right +
                       static_cast<float>(input.middleDrag.y) * mCamera.up) *
                      worldPerPixel;
            placeOrbitCamera();
        }
        if (input.scroll != 0.0)
            zoom(std::pow(kZoomPerNotch, static_cast<float>(input.scroll)));
        return;
    }

    // Fly.
    if (input.rightDrag != glm::dvec2(0.0)) {
        const float yaw = azimuthOf(mCamera.forward) -
                          static_cast<float>(input.rightDrag.x) * kDegreesPerPixel;
        const float pitch = std::clamp(
                elevationOf(mCamera.forward) -
                        static_cast<float>(input.rightDrag.y) * kDegreesPerPixel,
                -kMaxElevation,
                kMaxElevation);
        const runtime::Camera turned = runtime::Camera::lookAt(
                mCamera.eye, mCamera.eye + direction(yaw, pitch), kWorldUp, mCamera.fovY);
        mCamera.forward = turned.forward;
        mCamera.up = turned.up;
    }
    if (input.scroll != 0.0)
        mFlySpeedScale = std::clamp(
                mFlySpeedScale * std::pow(1.25f, static_cast<float>(input.scroll)), 1e-3f, 1e3f);
    glm::vec3 move(0.0f);
    const glm::vec3 right = glm::normalize(glm::cross(mCamera.forward, mCamera.up));
    if (input.isDown(Key::W))
        move += mCamera.forward;
    if (input.isDown(Key::S))
        move -= mCamera.forward;
    if (input.isDown(Key::D))
        move += right;
    if (input.isDown(Key::A))
        move -= right;
    if (input.isDown(Key::E))
        move += kWorldUp;
    if (input.isDown(Key::Q))
        move -= kWorldUp;
    if (glm::dot(move, move) > 0.0f) {
        const float speed = kFlySpeedRadii * mRadius * mFlySpeedScale *
                            (input.isDown(Key::Shift) ? kFastFactor : 1.0f);
        mCamera.eye += glm::normalize(move) * speed * static_cast<float>(seconds);
    }
}

runtime::Camera CameraController::camera() const {
    runtime::Camera camera = mCamera;
    camera.fitClipPlanes(mBounds);
    return camera;
}

} // namespace ff::viewer
