#pragma once

// Bounds-checked accessor reading. Every byte range an accessor touches (its bufferView, the
// view's buffer, the stride walk, the sparse index and value views) is checked against the
// loaded buffers before anything is read; tinygltf itself checks none of this.

#include "TinyGltf.h"

#include <ff/storage/Status.h>

#include <glm/glm.hpp>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace ff::builder {

/** An accessor decoded to floats: `count` elements of `components` (1..4) values each.
 *  Normalized integers are mapped to [0,1] / [-1,1]; other integers keep their value. */
struct FloatArray {
    std::vector<float> values;
    std::size_t count = 0;
    int components = 0;

    /** Element `i` widened to a vec4 whose missing components are `fill`. */
    glm::vec4 get(std::size_t i, glm::vec4 fill = glm::vec4(0.0f)) const noexcept;
};

/** Bytes per component of a glTF component type, 0 for an unknown type. */
std::size_t componentSizeOf(int componentType) noexcept;

/** Components of a glTF accessor type (SCALAR = 1 ... MAT4 = 16), 0 for an unknown type. */
int componentCountOf(int type) noexcept;

/** Checks that accessor `index` exists and that every range it reads lies inside its buffers.
 *  Errors: InvalidInput "accessor N: ...". */
[[nodiscard]] Status checkAccessor(const tinygltf::Model& model, int index);

/** Reads a SCALAR..VEC4 accessor of any component type (sparse applied). Checks first. */
[[nodiscard]] Result<FloatArray> readFloatAccessor(const tinygltf::Model& model, int index);

/** Reads an index accessor (SCALAR of uint8/16/32, sparse applied). Checks first. */
[[nodiscard]] Result<std::vector<std::uint32_t>>
readIndexAccessor(const tinygltf::Model& model, int index);

} // namespace ff::builder
