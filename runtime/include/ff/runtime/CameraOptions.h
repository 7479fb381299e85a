#pragma once

#include <ff/runtime/Camera.h>
#include <ff/runtime/CameraPath.h>
#include <ff/storage/SceneIndex.h>
#include <ff/storage/Status.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace ff::runtime {

/** How a user names a view (render and view flags, bench scenarios): a stored glTF camera, an
 *  eye and target, an orbit about the scene, or a frame of a camera path. */
struct CameraOptions {
    std::string camera;  ///< "gltf:N": the N-th camera of the source glTF
    std::string eye;     ///< "x,y,z"
    std::string target;  ///< "x,y,z"
    std::string up = "0,1,0";
    float fovDegrees = 45.0f;
    float distance = 3.0f;   ///< in scene radii
    float azimuth = 30.0f;   ///< degrees about +Y from +Z
    float elevation = 20.0f; ///< degrees
    std::string path;        ///< camera path JSON (docs/camera-paths.md)
    std::int64_t pathFrame = -1; ///< frame of `path`; -1 = not given (frame 0)

    /** Resolves the flags against the scene (bounds, stored glTF cameras, camera path). */
    [[nodiscard]] Result<Camera> resolve(const storage::SceneIndex& scene) const;
};

/** Bounds of a scene file, in its own frame (where the runtime draws). */
Bounds sceneBounds(const storage::SceneIndex& scene);

/** World position of the scene file frame's origin (storage/FORMAT.md "The file frame"): world
 *  coordinates the user gives (--eye, camera paths, glTF cameras) minus this are file frame. */
glm::dvec3 sceneOrigin(const storage::SceneIndex& scene);

/** A camera of the source glTF, as the builder stored it in the scene's metadata ("cameras"). */
struct StoredCamera {
    std::string name;
    bool perspective = true;
    glm::dvec3 eye{0.0};                  ///< world space
    glm::vec3 forward{0.0f, 0.0f, -1.0f}; ///< unit
    glm::vec3 up{0.0f, 1.0f, 0.0f};       ///< unit
    std::optional<float> yfovRadians;     ///< perspective only
    float ymag = 1.0f;                    ///< orthographic half height
};

/** The scene's stored glTF cameras in glTF order; empty if it has none (e.g. generated scenes).
 *  Corrupt if an entry is malformed. */
[[nodiscard]] Result<std::vector<StoredCamera>> storedCameras(const storage::SceneIndex& scene);

/** Reads and validates a camera path file; errors name the file. */
[[nodiscard]] Result<CameraPath> readCameraPath(const std::string& file);

} // namespace ff::runtime
