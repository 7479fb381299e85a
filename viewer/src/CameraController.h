#pragma once

#include "Window.h"

#include <ff/runtime/Camera.h>

#include <glm/glm.hpp>

namespace ff::viewer {

enum class NavigationMode { Orbit, Fly };

/**
 * Moves the `view` window's camera. Orbit: left drag turns the camera about a pivot (azimuth
 * about +Y, elevation up to ±89°), middle drag pans the pivot, scroll zooms. Fly: W/A/S/D move
 * along the view, Q/E down/up, right drag looks around, scroll scales the speed; the speed is
 * half the scene radius per second (Shift: five times that). Tab switches, R goes back to the
 * initial view. The near and far planes are refitted to the scene for every camera() call.
 * No GL, no GLFW: input comes as an InputState.
 */
class CameraController {
public:
    /** Starts at `initial` (shown exactly as given), orbiting about `pivot`. */
    CameraController(
            const runtime::Camera& initial, const glm::vec3& pivot, const runtime::Bounds& bounds);

    /** Applies one frame of input; `seconds` is the frame's duration, `viewportHeight` the
     *  window's height in screen pixels (for panning). */
    void update(const InputState& input, double seconds, int viewportHeight);
    /** Turns about the pivot: azimuth (about +Y) and elevation, degrees (scripts, keys). */
    void orbit(float azimuthDegrees, float elevationDegrees);
    /** Multiplies the distance to the pivot by `factor` (> 0). */
    void zoom(float factor);
    void toggleMode();
    void reset();

    NavigationMode mode() const { return mMode; }
    /** The camera with its clip planes fitted to the scene bounds. */
    runtime::Camera camera() const;
    const glm::vec3& pivot() const { return mPivot; }

private:
    /** Rebuilds the orbit state (angles, distance) from the camera and the pivot. */
    void syncOrbitFromCamera();
    void placeOrbitCamera();

    runtime::Camera mInitial;
    glm::vec3 mInitialPivot;
    runtime::Bounds mBounds;
    float mRadius;
    runtime::Camera mCamera;
    NavigationMode mMode = NavigationMode::Orbit;
    glm::vec3 mPivot;
    float mDistance = 1.0f;
    float mAzimuth = 0.0f;   ///< degrees about +Y from +Z (as Camera::orbit)
    float mElevation = 0.0f; ///< degrees
    float mFlySpeedScale = 1.0f;
};

} // namespace ff::viewer
