#pragma once

#include "TinyGltf.h"

#include <ff/storage/Status.h>

#include <filesystem>
#include <string>
#include <vector>

namespace ff::builder {

/**
 * Reads a .gltf or .glb file (told apart by the GLB magic, not the extension) into a tinygltf
 * model. GLB framing and the JSON's byte-order mark are checked here, before tinygltf sees the
 * bytes. Images are NOT decoded: each image keeps its encoded bytes in `Image::image` with
 * width/height 0; TextureSampler decodes the few that are used as base colour. Draco primitives
 * are left compressed (see GltfDraco.h). tinygltf's warnings are appended to `warnings`; its
 * errors become the Status message. Never throws.
 */
[[nodiscard]] Status loadGltfModel(
        const std::filesystem::path& path,
        tinygltf::Model& model,
        std::vector<std::string>& warnings) noexcept;

} // namespace ff::builder
