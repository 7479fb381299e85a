#pragma once

// What the builder keeps of a glTF material: the base colour (factor, texture, the texture
// coordinates it reads, with KHR_texture_transform applied) and whether it is lit at all
// (KHR_materials_unlit). Everything else (metallic-roughness, normal maps, emission) is dropped:
// vertex colours and colour cubes carry one colour under the one shading model.

#include "TinyGltf.h"

#include <ff/storage/Status.h>

#include <glm/glm.hpp>

#include <string>

namespace ff::builder {

inline constexpr const char* kTextureTransformExtension = "KHR_texture_transform";
inline constexpr const char* kUnlitExtension = "KHR_materials_unlit";

/**
 * KHR_texture_transform of one texture reference: uv' = T(offset) R(rotation) S(scale) uv, with
 * the extension's rotation matrix [[cos r, sin r], [-sin r, cos r]] (counter-clockwise in UV
 * space, whose v axis points down the image). Identity without the extension.
 */
struct UvTransform {
    glm::dvec2 offset{0.0};
    double rotation = 0.0; ///< radians
    glm::dvec2 scale{1.0};

    [[nodiscard]] glm::vec2 apply(glm::vec2 uv) const noexcept;
    [[nodiscard]] bool isIdentity() const noexcept;
};

struct BaseColorInput {
    glm::vec4 factor{1.0f}; ///< linear RGBA
    int texture = -1;       ///< textures[] index, -1 for none
    int texCoord = 0;       ///< TEXCOORD_<n> the texture reads (the transform's override applied)
    UvTransform uvTransform;
    bool unlit = false; ///< KHR_materials_unlit
};

/**
 * The base colour inputs of materials[material] (-1: glTF's default material, white and lit).
 * Fails (InvalidInput) where KHR_texture_transform's values are not what the extension allows:
 * offset and scale two finite numbers, rotation one, texCoord a non-negative integer.
 */
[[nodiscard]] Result<BaseColorInput> baseColorInput(const tinygltf::Model& model, int material);

/** A string equal for two inputs exactly when they give the same vertex colours. */
[[nodiscard]] std::string baseColorKey(const BaseColorInput& input);

} // namespace ff::builder
