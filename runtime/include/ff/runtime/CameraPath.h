#pragma once

// Camera paths: keyframed camera motion for walk-throughs and paging-behaviour tests.
//
// A path is a list of keyframes (time, position, orientation, field of view) plus an
// interpolation mode and a frame sampling (a rate or a count). The JSON format is documented in
// docs/camera-paths.md; generators fitted to a scene's bounds live in CameraPathGenerators.h.
//
//   fromJson / create ──validate──▶ CameraPath ──pose(t) / sample(t)──▶ Camera
//                                              └─frameCount() / frameTime(i)─▶ the frames to draw
//
// Interpolation (see CameraPath.cpp for the references):
//  - Linear: positions and fields of view are lerped in time, orientations slerped (shortest arc).
//  - Spline: positions follow the centripetal Catmull-Rom curve through the keyframes (knot
//    spacing |ΔP|^½, Yuksel et al. 2011: no cusps or self-intersections within a segment); time is
//    mapped onto the curve's knots by a monotone cubic (Fritsch & Carlson 1980), so the camera
//    passes through every keyframe at its time, never runs backwards, and moves C1-smoothly in
//    time. Orientations follow Shoemake's squad (C1 where keyframes are evenly spaced in time,
//    as generated paths are; continuous otherwise); fields of view the monotone cubic.

#include <ff/runtime/Camera.h>
#include <ff/storage/Status.h>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace ff::runtime {

enum class PathInterpolation { Linear, Spline };

/** "linear" / "spline". */
const char* pathInterpolationName(PathInterpolation interpolation) noexcept;

/**
 * One keyframe. The orientation maps camera axes to world axes as in glTF: the camera looks along
 * orientation * (0,0,-1) with orientation * (0,1,0) up. Units: seconds, world units, degrees.
 */
struct CameraKeyframe {
    double time = 0.0;
    glm::dvec3 position{0.0};
    glm::dquat orientation{1.0, 0.0, 0.0, 0.0}; ///< unit (glm order: w, x, y, z)
    double fovDegrees = 45.0;                   ///< vertical field of view, in (0, 180)
    std::string name;                           ///< optional label (e.g. the glTF camera's name)
};

/** The interpolated state of a path at one time (double precision, unlike Camera). */
struct CameraPose {
    glm::dvec3 position{0.0};
    glm::dquat orientation{1.0, 0.0, 0.0, 0.0}; ///< unit
    double fovDegrees = 45.0;

    glm::dvec3 forward() const { return orientation * glm::dvec3(0.0, 0.0, -1.0); }
    glm::dvec3 up() const { return orientation * glm::dvec3(0.0, 1.0, 0.0); }
};

/**
 * The orientation of a camera looking along `forward` with `upHint` as nearly up as possible.
 * Both must be non-zero and not parallel (asserted; validate input before calling).
 */
glm::dquat lookOrientation(const glm::dvec3& forward, const glm::dvec3& upHint);

/** Which frames of the path are drawn: either `fps` frames per second from the first keyframe's
 *  time, or `count` frames spread evenly over the path, both ends included. */
struct FrameSampling {
    double fps = 30.0; ///< used when count == 0; > 0
    std::int64_t count = 0;

    static FrameSampling rate(double framesPerSecond) { return {framesPerSecond, 0}; }
    static FrameSampling frames(std::int64_t frameCount) { return {0.0, frameCount}; }
};

/**
 * A validated camera path (immutable; a cheap-to-copy value). Thread-safety: const methods may be
 * called concurrently.
 */
class CameraPath {
public:
    /**
     * Validates and precomputes the interpolation. Errors (InvalidArgument) for: no keyframes,
     * non-finite values, times not strictly increasing, quaternions far from unit length (> 1e-3;
     * normalised otherwise), fov outside (0, 180), fps <= 0 with count == 0, count < 0.
     */
    [[nodiscard]] static Result<CameraPath>
    create(std::vector<CameraKeyframe> keyframes,
           PathInterpolation interpolation,
           FrameSampling sampling = {});

    /** Parses the JSON format of docs/camera-paths.md. Errors are InvalidInput and name the key,
     *  e.g. "keyframes[2].position[1]: not a finite number". */
    [[nodiscard]] static Result<CameraPath> fromJson(std::string_view text);

    /** The JSON format of docs/camera-paths.md (orientations as quaternions, so a round trip
     *  through fromJson() is lossless). */
    std::string toJson() const;

    const std::vector<CameraKeyframe>& keyframes() const noexcept { return mKeyframes; }
    PathInterpolation interpolation() const noexcept { return mInterpolation; }
    const FrameSampling& sampling() const noexcept { return mSampling; }
    double startTime() const noexcept { return mKeyframes.front().time; }
    double endTime() const noexcept { return mKeyframes.back().time; }

    /** The state at `time` seconds, clamped to [startTime(), endTime()]. Exact at keyframes. */
    CameraPose pose(double time) const;

    /** The camera at `time` (clamped), moved into a frame whose origin lies at `frameOrigin`
     *  (a scene file's origin: paths are in world coordinates, drawing happens in the file's
     *  frame; the subtraction is done in double). Clip planes are Camera's defaults: call
     *  fitClipPlanes() with the scene's bounds before drawing. */
    Camera sample(double time, const glm::dvec3& frameOrigin = glm::dvec3(0.0)) const;

    /** The same path moved by `offset` (e.g. from a scene file's frame into the world). */
    CameraPath translated(const glm::dvec3& offset) const;

    /** Number of frames (>= 1). */
    std::int64_t frameCount() const noexcept;
    /** Time of frame `index` in [0, frameCount()) (asserted), within [startTime(), endTime()]. */
    double frameTime(std::int64_t index) const;

private:
    CameraPath() = default;

    CameraPose poseInSegment(std::size_t segment, double time) const;

    std::vector<CameraKeyframe> mKeyframes;
    PathInterpolation mInterpolation = PathInterpolation::Linear;
    FrameSampling mSampling;
    // Spline precomputation (empty for Linear): centripetal knots, the monotone-cubic slopes of
    // knot(time) and fov(time), hemisphere-aligned orientations and squad's inner quaternions.
    std::vector<double> mKnots;
    std::vector<double> mKnotSlopes;
    std::vector<double> mFovSlopes;
    std::vector<glm::dquat> mAligned;
    std::vector<glm::dquat> mSquadInner;
};

} // namespace ff::runtime
