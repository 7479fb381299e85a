#pragma once

// The one shading model used everywhere (DESIGN.md, "Scene model"): the builder bakes it into
// color cubes and the renderer applies it to geometry, so that cubes, geometry and references
// are comparable pixel for pixel. Lambert with a fixed world-space light, two-sided (the
// absolute cosine), plus ambient: cube faces cannot know which side a viewer will see.

#include <array>
#include <cmath>

namespace ff::storage {

/** Unit direction towards the light, world space. */
inline constexpr std::array<float, 3> kLightDirection = {0.3714172f, 0.8356886f, 0.4045662f};
inline constexpr float kAmbient = 0.35f;
inline constexpr float kDiffuse = 0.65f;

/** Light factor of an unlit surface (KHR_materials_unlit): its colour as it is. */
inline constexpr float kUnlitShading = 1.0f;

/** Light factor for a unit normal: kAmbient + kDiffuse * |n . L|. */
inline float shadingFactor(float nx, float ny, float nz) noexcept {
    const float cosine = nx * kLightDirection[0] + ny * kLightDirection[1] + nz * kLightDirection[2];
    return kAmbient + kDiffuse * std::fabs(cosine);
}

} // namespace ff::storage
