#pragma once

// Where a camera path cuts: the frames a viewer jumps to, as opposed to frames it moves to. A
// replay counts "frames to full quality" from each cut, so a cut must be a teleport (or the cold
// start), never fast but continuous motion: an orbit that moves a quarter of the scene radius a
// frame still moves continuously, and the streaming cache can follow it by prefetching.

#include <ff/runtime/CameraPath.h>

#include <glm/glm.hpp>

#include <vector>

namespace ff::runtime {

/** An eye step counts as a cut only above this share of the scene radius. */
inline constexpr double kCutMinimumStep = 0.05;
/** ... and only when it exceeds both neighbouring steps this many times. */
inline constexpr double kCutStepRatio = 4.0;

/**
 * One flag per frame of `path`: true where the frame is a cut. Frame 0 always is (the cold start);
 * frame f > 0 is when the eye's step from f - 1 to f is longer than kCutMinimumStep x
 * `sceneRadius` and longer than kCutStepRatio x each neighbouring step (f - 2 to f - 1 and f to
 * f + 1; a missing neighbour counts as 0). A teleport path's jumps sit between holds that do not
 * move at all; an orbit's or a fly-through's steps change smoothly and never cut. Eyes are
 * sampled relative to `frameOrigin` (the scene file's origin), where floats keep their precision.
 */
[[nodiscard]] std::vector<bool> findPathCuts(
        const CameraPath& path,
        double sceneRadius,
        const glm::dvec3& frameOrigin = glm::dvec3(0.0));

} // namespace ff::runtime
