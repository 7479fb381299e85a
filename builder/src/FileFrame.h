#pragma once

// The file frame (storage/FORMAT.md "The file frame"): every coordinate a scene file stores is
// relative to a double-precision origin, picked once the builder has seen every instance.

#include <ff/storage/SceneFormat.h>

#include <glm/glm.hpp>

namespace ff::builder {

/** World-space bounds of a scene's instances, accumulated in double. */
class WorldBounds {
public:
    /** Adds the prototype's bounds as `transform` places them in the world. */
    void add(const glm::dmat4& transform, const storage::PrototypeRecord& prototype) noexcept;
    bool empty() const noexcept { return mMin.x > mMax.x; }
    glm::dvec3 min() const noexcept { return mMin; }
    glm::dvec3 max() const noexcept { return mMax; }

private:
    glm::dvec3 mMin{1.0};
    glm::dvec3 mMax{-1.0};
};

/** Scenes whose centre lies within this many scene radii of the world origin keep origin 0:
 *  float coordinates then lose at most ~1e-6 of the scene's size, and files stay in world
 *  coordinates. */
inline constexpr double kFileOriginRadii = 16.0;

/** The world origin, or the centre of `bounds` when that is more than kFileOriginRadii scene
 *  radii away from it. */
glm::dvec3 chooseFileOrigin(const WorldBounds& bounds) noexcept;

} // namespace ff::builder
