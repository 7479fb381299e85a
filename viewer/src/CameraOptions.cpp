#include "CameraOptions.h"

#include "Units.h"

#include <nlohmann/json.hpp>

#include <charconv>
#include <cmath>

namespace ff::viewer {

void CameraOptions::addTo(CLI::App& app) {
    app.add_option("--camera", camera, "Camera stored from the source glTF, e.g. gltf:0");
    app.add_option("--eye", eye, "Camera position x,y,z (with --target)");
    app.add_option("--target", target, "Point looked at x,y,z (with --eye)");
    app.add_option("--up", up, "Up direction x,y,z")->capture_default_str();
    app.add_option("--fov", fovDegrees, "Vertical field of view, degrees")->capture_default_str();
    app.add_option("--distance", distance, "Orbit camera: distance from the centre in scene radii")->capture_default_str();
    app.add_option("--azimuth", azimuth, "Orbit camera: degrees about +Y, from +Z")->capture_default_str();
    app.add_option("--elevation", elevation, "Orbit camera: degrees above the horizon")->capture_default_str();
}

runtime::Bounds sceneBounds(const storage::SceneFile& scene) {
    const auto& h = scene.header();
    return {{h.boundsMin[0], h.boundsMin[1], h.boundsMin[2]}, {h.boundsMax[0], h.boundsMax[1], h.boundsMax[2]}};
}

Result<runtime::Camera> CameraOptions::resolve(const storage::SceneFile& scene) const {
    const runtime::Bounds bounds = sceneBounds(scene);
    if (!(fovDegrees > 0.0f && fovDegrees < 179.0f))
        return Status(ErrorCode::InvalidArgument, "--fov must be between 0 and 179 degrees");
    const float fov = glm::radians(fovDegrees);
    if (!camera.empty()) {
        if (camera.rfind("gltf:", 0) != 0)
            return Status(ErrorCode::InvalidArgument, "--camera must look like gltf:0");
        int index = -1;
        const std::string number = camera.substr(5);
        const auto [end, error] = std::from_chars(number.data(), number.data() + number.size(), index);
        if (error != std::errc() || end != number.data() + number.size() || index < 0)
            return Status(ErrorCode::InvalidArgument, "--camera " + camera + ": expected gltf:<index>");
        const nlohmann::json metadata = nlohmann::json::parse(scene.metadataJson(), nullptr, false);
        const nlohmann::json cameras = metadata.is_object() ? metadata.value("cameras", nlohmann::json::array())
                                                            : nlohmann::json::array();
        if (!cameras.is_array() || static_cast<std::size_t>(index) >= cameras.size())
            return Status(ErrorCode::NotFound, "--camera " + camera + ": the scene has " +
                                                       std::to_string(cameras.is_array() ? cameras.size() : 0) +
                                                       " glTF camera(s)");
        const nlohmann::json& c = cameras[static_cast<std::size_t>(index)];
        try {
            const auto v = [&c](const char* key) {
                const auto a = c.at(key);
                return glm::vec3(a.at(0).get<float>(), a.at(1).get<float>(), a.at(2).get<float>());
            };
            runtime::Camera result = runtime::Camera::lookAt(v("eye"), v("eye") + v("forward"), v("up"),
                                                             c.value("yfov", fov));
            result.orthographic = !c.value("perspective", true);
            result.orthoHalfHeight = c.value("ymag", 1.0f);
            result.fitClipPlanes(bounds);
            return result;
        } catch (const nlohmann::json::exception& e) {
            return Status(ErrorCode::Corrupt, "camera " + std::to_string(index) + " in the scene metadata: " + e.what());
        }
    }
    if (!eye.empty() || !target.empty()) {
        if (eye.empty() || target.empty())
            return Status(ErrorCode::InvalidArgument, "--eye and --target go together");
        FF_ASSIGN_OR_RETURN(const glm::vec3 e, parseVec3(eye));
        FF_ASSIGN_OR_RETURN(const glm::vec3 t, parseVec3(target));
        FF_ASSIGN_OR_RETURN(const glm::vec3 u, parseVec3(up));
        if (e == t)
            return Status(ErrorCode::InvalidArgument, "--eye and --target must differ");
        runtime::Camera result = runtime::Camera::lookAt(e, t, u, fov);
        result.fitClipPlanes(bounds);
        return result;
    }
    if (!(distance > 0.0f) || !std::isfinite(azimuth) || !std::isfinite(elevation))
        return Status(ErrorCode::InvalidArgument, "--distance must be positive");
    return runtime::Camera::orbit(bounds, distance, azimuth, elevation, fov);
}

} // namespace ff::viewer
