#pragma once

// KHR_draco_mesh_compression, decoded here rather than by tinygltf (see GltfLoader.cpp for why).

#include "GltfAccessors.h"
#include "TinyGltf.h"

#include <ff/storage/Status.h>

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace ff::builder {

inline constexpr const char* kDracoExtension = "KHR_draco_mesh_compression";

/** A Draco primitive's triangle list and the attributes named in its extension object. */
struct DracoPrimitive {
    std::vector<std::uint32_t> indices; ///< triangle list, 3 per face
    std::size_t vertexCount = 0;
    std::map<std::string, FloatArray, std::less<>> attributes;
};

/**
 * Decodes the primitive's KHR_draco_mesh_compression payload. The extension's bufferView is
 * range-checked first; unknown Draco attribute ids and failed decodes are InvalidInput errors
 * prefixed with `where` ("mesh 2 primitive 0"). Never throws.
 */
[[nodiscard]] Result<DracoPrimitive> decodeDracoPrimitive(
        const tinygltf::Model& model,
        const tinygltf::Primitive& primitive,
        const std::string& where) noexcept;

} // namespace ff::builder
