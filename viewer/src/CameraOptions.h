#pragma once

#include <ff/runtime/Camera.h>
#include <ff/storage/SceneFile.h>
#include <ff/storage/Status.h>

#include <CLI/CLI.hpp>

#include <optional>
#include <string>

namespace ff::viewer {

/** Camera flags shared by render, bench and (later) view/replay. */
struct CameraOptions {
    std::string camera;  ///< "gltf:N": the N-th camera of the source glTF
    std::string eye;     ///< "x,y,z"
    std::string target;  ///< "x,y,z"
    std::string up = "0,1,0";
    float fovDegrees = 45.0f;
    float distance = 3.0f;   ///< in scene radii
    float azimuth = 30.0f;   ///< degrees about +Y from +Z
    float elevation = 20.0f; ///< degrees

    void addTo(CLI::App& app);
    /** Resolves the flags against the scene (bounds, stored glTF cameras). */
    [[nodiscard]] Result<runtime::Camera> resolve(const storage::SceneFile& scene) const;
};

/** World bounds of a scene file. */
runtime::Bounds sceneBounds(const storage::SceneFile& scene);

} // namespace ff::viewer
