#include <ff/runtime/CameraOptions.h>

#include <ff/runtime/Units.h>

#include <nlohmann/json.hpp>

#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>

namespace ff::runtime {

Result<std::vector<StoredCamera>> storedCameras(const storage::SceneIndex& scene) {
    const nlohmann::json metadata = nlohmann::json::parse(scene.metadataJson(), nullptr, false);
    if (!metadata.is_object() || !metadata.contains("cameras"))
        return std::vector<StoredCamera>();
    const nlohmann::json& cameras = metadata["cameras"];
    if (!cameras.is_array())
        return Status(ErrorCode::Corrupt, "the scene metadata's \"cameras\" is not an array");
    std::vector<StoredCamera> result;
    for (std::size_t index = 0; index < cameras.size(); ++index) {
        const nlohmann::json& c = cameras[index];
        try {
            const auto v = [&c](const char* key) {
                const auto a = c.at(key);
                return glm::dvec3(a.at(0).get<double>(), a.at(1).get<double>(), a.at(2).get<double>());
            };
            StoredCamera camera;
            camera.name = c.value("name", std::string());
            camera.perspective = c.value("perspective", true);
            camera.eye = v("eye");
            camera.forward = glm::vec3(v("forward"));
            camera.up = glm::vec3(v("up"));
            if (c.contains("yfov"))
                camera.yfovRadians = c.at("yfov").get<float>();
            camera.ymag = c.value("ymag", 1.0f);
            result.push_back(std::move(camera));
        } catch (const nlohmann::json::exception& e) {
            return Status(ErrorCode::Corrupt, "camera " + std::to_string(index) + " in the scene metadata: " + e.what());
        }
    }
    return result;
}

Result<CameraPath> readCameraPath(const std::string& file) {
    std::ifstream in(file, std::ios::binary);
    if (!in)
        return Status(ErrorCode::NotFound, file + ": cannot open the camera path");
    std::ostringstream text;
    text << in.rdbuf();
    if (in.bad())
        return Status(ErrorCode::IoError, file + ": cannot read the camera path");
    auto path = CameraPath::fromJson(text.str());
    if (!path)
        return path.status().withContext(file);
    return path;
}

Bounds sceneBounds(const storage::SceneIndex& scene) {
    const auto& h = scene.header();
    return {{h.boundsMin[0], h.boundsMin[1], h.boundsMin[2]}, {h.boundsMax[0], h.boundsMax[1], h.boundsMax[2]}};
}

glm::dvec3 sceneOrigin(const storage::SceneIndex& scene) {
    const auto& o = scene.header().origin;
    return {o[0], o[1], o[2]};
}

Result<Camera> CameraOptions::resolve(const storage::SceneIndex& scene) const {
    const Bounds bounds = sceneBounds(scene);
    const glm::dvec3 origin = sceneOrigin(scene);
    if (!(fovDegrees > 0.0f && fovDegrees < 179.0f))
        return Status(ErrorCode::InvalidArgument, "--fov must be between 0 and 179 degrees");
    const float fov = glm::radians(fovDegrees);
    if (!path.empty()) {
        if (!camera.empty() || !eye.empty() || !target.empty())
            return Status(ErrorCode::InvalidArgument, "--path does not go with --camera, --eye or --target");
        FF_ASSIGN_OR_RETURN(const CameraPath cameraPath, readCameraPath(path));
        const std::int64_t frame = std::max<std::int64_t>(pathFrame, 0);
        if (frame >= cameraPath.frameCount())
            return Status(ErrorCode::InvalidArgument, "--path-frame " + std::to_string(frame) + ": " + path + " has " +
                                                              std::to_string(cameraPath.frameCount()) + " frames (0 to " +
                                                              std::to_string(cameraPath.frameCount() - 1) + ")");
        Camera result = cameraPath.sample(cameraPath.frameTime(frame), origin);
        result.fitClipPlanes(bounds);
        return result;
    }
    if (pathFrame >= 0)
        return Status(ErrorCode::InvalidArgument, "--path-frame needs --path");
    if (!camera.empty()) {
        if (camera.rfind("gltf:", 0) != 0)
            return Status(ErrorCode::InvalidArgument, "--camera must look like gltf:0");
        int index = -1;
        const std::string number = camera.substr(5);
        const auto [end, error] = std::from_chars(number.data(), number.data() + number.size(), index);
        if (error != std::errc() || end != number.data() + number.size() || index < 0)
            return Status(ErrorCode::InvalidArgument, "--camera " + camera + ": expected gltf:<index>");
        FF_ASSIGN_OR_RETURN(const std::vector<StoredCamera> cameras, storedCameras(scene));
        if (static_cast<std::size_t>(index) >= cameras.size())
            return Status(ErrorCode::NotFound, "--camera " + camera + ": the scene has " +
                                                       std::to_string(cameras.size()) + " glTF camera(s)");
        const StoredCamera& c = cameras[static_cast<std::size_t>(index)];
        const glm::vec3 eyeInFile(c.eye - origin);
        Camera result = Camera::lookAt(eyeInFile, eyeInFile + c.forward, c.up, c.yfovRadians.value_or(fov));
        result.orthographic = !c.perspective;
        result.orthoHalfHeight = c.ymag;
        result.fitClipPlanes(bounds);
        return result;
    }
    if (!eye.empty() || !target.empty()) {
        if (eye.empty() || target.empty())
            return Status(ErrorCode::InvalidArgument, "--eye and --target go together");
        FF_ASSIGN_OR_RETURN(const glm::dvec3 worldEye, parseDVec3(eye));
        FF_ASSIGN_OR_RETURN(const glm::dvec3 worldTarget, parseDVec3(target));
        FF_ASSIGN_OR_RETURN(const glm::vec3 u, parseVec3(up));
        const glm::vec3 e(worldEye - origin);
        const glm::vec3 t(worldTarget - origin);
        if (e == t)
            return Status(ErrorCode::InvalidArgument, "--eye and --target must differ");
        Camera result = Camera::lookAt(e, t, u, fov);
        result.fitClipPlanes(bounds);
        return result;
    }
    if (!(distance > 0.0f) || !std::isfinite(azimuth) || !std::isfinite(elevation))
        return Status(ErrorCode::InvalidArgument, "--distance must be positive");
    return Camera::orbit(bounds, distance, azimuth, elevation, fov);
}

} // namespace ff::runtime
