#pragma once

// The checks tinygltf does not do (it accepts about half of the glTF validator's invalid cases).
// Everything the importer will read is checked here, before anything reaches the sink: the
// node graph, every reference it follows, every bufferView range, the range of every accessor a
// mesh or EXT_mesh_gpu_instancing uses, attribute counts, index values, required extensions.
// What only animation or skinning would read (samplers, skins, joints' values, morph targets)
// is deliberately not checked: the importer ignores it, so it must not cause a refusal.

#include "TinyGltf.h"

#include <ff/storage/Status.h>

#include <string_view>

namespace ff::builder {

inline constexpr std::string_view kInstancingExtension = "EXT_mesh_gpu_instancing";

/** Required extensions the importer handles. */
bool isSupportedRequiredExtension(std::string_view name) noexcept;

/**
 * Returns InvalidInput naming the first broken object ("accessor 3: range past the end of
 * bufferView 1", "node 2: loop through its children"), Unsupported for a required extension
 * we do not handle ("required extension X is not supported"), or OK.
 */
[[nodiscard]] Status validateGltfModel(const tinygltf::Model& model);

} // namespace ff::builder
