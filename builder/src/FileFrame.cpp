#include "FileFrame.h"

#include <algorithm>

namespace ff::builder {

void WorldBounds::add(const glm::dmat4& transform, const storage::PrototypeRecord& prototype) noexcept {
    const glm::dvec3 lo(prototype.boundsMin[0], prototype.boundsMin[1], prototype.boundsMin[2]);
    const glm::dvec3 hi(prototype.boundsMax[0], prototype.boundsMax[1], prototype.boundsMax[2]);
    for (int corner = 0; corner < 8; ++corner) {
        const glm::dvec3 local((corner & 1) ? hi.x : lo.x, (corner & 2) ? hi.y : lo.y, (corner & 4) ? hi.z : lo.z);
        const glm::dvec3 world(transform * glm::dvec4(local, 1.0));
        if (empty()) {
            mMin = mMax = world;
        } else {
            mMin = glm::min(mMin, world);
            mMax = glm::max(mMax, world);
        }
    }
}

glm::dvec3 chooseFileOrigin(const WorldBounds& bounds) noexcept {
    if (bounds.empty())
        return glm::dvec3(0.0);
    const glm::dvec3 centre = 0.5 * (bounds.min() + bounds.max());
    const double radius = 0.5 * glm::length(bounds.max() - bounds.min());
    return glm::length(centre) > kFileOriginRadii * radius ? centre : glm::dvec3(0.0);
}

} // namespace ff::builder
