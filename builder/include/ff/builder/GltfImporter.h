#pragma once

#include <ff/builder/SceneSink.h>
#include <ff/storage/Status.h>

#include <glm/glm.hpp>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace ff::builder {

/** A glTF camera placed in the world by its node's transform. */
struct GltfCamera {
    std::string name;
    bool perspective = true;
    glm::dvec3 eye{0.0};                  ///< world space, double like node transforms
    glm::vec3 forward{0.0f, 0.0f, -1.0f}; ///< unit, world space (the node's -Z)
    glm::vec3 up{0.0f, 1.0f, 0.0f};       ///< unit, world space (the node's +Y)
    float yfovRadians = 0.8f;             ///< perspective only
    float aspectRatio = 0.0f;             ///< 0 = not given
    float znear = 0.01f;
    float zfar = 0.0f;        ///< 0 = infinite
    float xmag = 1.0f;        ///< orthographic only
    float ymag = 1.0f;        ///< orthographic only
};

struct GltfImportReport {
    /** Triangles the file declares for its drawn meshes (modes 4/5/6, per instance),
     *  counted from accessor counts before any triangle is dropped. */
    std::uint64_t declaredTriangles = 0;
    /** Triangles passed to the sink (per prototype, counted once). */
    std::uint64_t emittedTriangles = 0;
    std::uint32_t prototypes = 0;
    std::uint64_t instances = 0;
    std::uint64_t skippedPrimitives = 0; ///< points/lines, counted and named in warnings
    std::vector<GltfCamera> cameras;
    std::vector<std::string> warnings; ///< one line each, e.g. "mesh 3: skinned, taken in rest pose"
};

struct GltfImportOptions {
    /** Scene index to import; -1 = the file's default scene (or scene 0). */
    int scene = -1;
};

/**
 * Reads a glTF 2.0 file (.gltf or .glb) and streams it into `sink`.
 *
 * - Each glTF mesh becomes one prototype; every node that references it becomes an instance
 *   with the node's world transform (TRS or matrix). EXT_mesh_gpu_instancing adds one instance
 *   per instanced transform. Nothing is flattened.
 * - Triangles, strips and fans, indexed or not; KHR_draco_mesh_compression;
 *   KHR_mesh_quantization (normalized integer attributes); sparse accessors.
 * - Colour = baseColorFactor x COLOR_0 x baseColorTexture sampled bilinearly at each vertex's
 *   UV (in linear space). Skinned and morphed meshes are taken in their rest pose.
 * - Everything tinygltf does not check is checked here (node loops, unresolved references,
 *   out-of-range indices, views past their buffers, unsupported required extensions): such a
 *   file is refused with ErrorCode::InvalidInput or Unsupported naming the offending object.
 */
[[nodiscard]] Result<GltfImportReport> importGltf(
        const std::filesystem::path& path, ISceneSink& sink, const GltfImportOptions& options = {});

} // namespace ff::builder
