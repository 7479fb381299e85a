#include <ff/runtime/PathCuts.h>

#include <algorithm>
#include <cstddef>

namespace ff::runtime {

std::vector<bool>
findPathCuts(const CameraPath& path, double sceneRadius, const glm::dvec3& frameOrigin) {
    const auto frames = static_cast<std::size_t>(std::max<std::int64_t>(path.frameCount(), 0));
    std::vector<bool> cuts(frames, false);
    if (frames == 0)
        return cuts;
    // step[f]: how far the eye moves from frame f - 1 to frame f (step[0] = 0).
    std::vector<double> step(frames, 0.0);
    glm::dvec3 previous(path.sample(path.frameTime(0), frameOrigin).eye);
    for (std::size_t f = 1; f < frames; ++f) {
        const glm::dvec3 eye(
                path.sample(path.frameTime(static_cast<std::int64_t>(f)), frameOrigin).eye);
        step[f] = glm::length(eye - previous);
        previous = eye;
    }
    cuts[0] = true;
    for (std::size_t f = 1; f < frames; ++f) {
        const double before = f >= 2 ? step[f - 1] : 0.0;
        const double after = f + 1 < frames ? step[f + 1] : 0.0;
        cuts[f] = step[f] > kCutMinimumStep * sceneRadius &&
                  step[f] > kCutStepRatio * std::max(before, after);
    }
    return cuts;
}

} // namespace ff::runtime
