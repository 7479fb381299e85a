#include "CameraFlags.h"
#include "Commands.h"
#include "OutputFile.h"

#include <ff/runtime/CameraPath.h>
#include <ff/runtime/CameraPathGenerators.h>
#include <ff/storage/SceneFile.h>

#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

namespace ff::viewer {

namespace {

struct PathArgs {
    std::string kind;
    std::string scene;
    std::string output;
    runtime::PathGeneratorOptions generator;
    std::string legs; ///< walk: world coordinates
    CLI::Option* framesOption = nullptr; ///< whether --frames was given (gltf paths)
};

/** One keyframe per stored glTF camera, 1 s apart, smoothly interpolated. */
Result<runtime::CameraPath> gltfCameraPath(const storage::SceneFile& scene, const PathArgs& args) {
    FF_ASSIGN_OR_RETURN(const std::vector<runtime::StoredCamera> cameras, runtime::storedCameras(scene));
    if (cameras.empty())
        return Status(
                ErrorCode::NotFound,
                "the scene has no stored glTF cameras (it was built from a generator "
                "or from a glTF file without cameras)");
    std::vector<runtime::CameraKeyframe> keyframes;
    for (std::size_t i = 0; i < cameras.size(); ++i) {
        const runtime::StoredCamera& c = cameras[i];
        if (!c.perspective)
            std::fprintf(
                    stderr,
                    "farfield path: camera %zu%s%s is orthographic; the path views it in "
                    "perspective "
                    "with --fov %g\n",
                    i,
                    c.name.empty() ? "" : " ",
                    c.name.c_str(),
                    args.generator.fovDegrees);
        runtime::CameraKeyframe k;
        k.time = static_cast<double>(i);
        k.position = c.eye;
        if (!(glm::dot(c.forward, c.forward) > 0.0f))
            return Status(
                    ErrorCode::Corrupt,
                    "camera " + std::to_string(i) + " in the scene metadata has no direction");
        k.orientation = runtime::lookOrientation(glm::dvec3(c.forward), glm::dvec3(c.up));
        k.fovDegrees = c.perspective && c.yfovRadians
                               ? glm::degrees(static_cast<double>(*c.yfovRadians))
                               : args.generator.fovDegrees;
        k.name = c.name;
        keyframes.push_back(std::move(k));
    }
    const runtime::FrameSampling sampling =
            args.framesOption->count() > 0 ? runtime::FrameSampling::frames(args.generator.frames)
                                           : runtime::FrameSampling::rate(args.generator.fps);
    auto path = runtime::CameraPath::create(
            std::move(keyframes), runtime::PathInterpolation::Spline, sampling);
    if (!path)
        return Status(ErrorCode::Corrupt, "the scene's glTF cameras: " + path.status().message());
    return path;
}

int runPath(const PathArgs& args) {
    auto output = PendingOutput::reserve(args.output, OutputKind::Text);
    if (!output)
        return reportError("path", output.status());
    auto scene = storage::SceneFile::open(args.scene);
    if (!scene)
        return reportError("path", scene.status().withContext(args.scene));
    const runtime::Bounds bounds = runtime::sceneBounds(**scene);

    Result<runtime::CameraPath> path = Status(ErrorCode::Internal, "no path made");
    if (args.kind == "orbit")
        path = runtime::makeOrbitPath(bounds, args.generator);
    else if (args.kind == "flythrough")
        path = runtime::makeFlythroughPath(bounds, args.generator);
    else if (args.kind == "teleports")
        path = runtime::makeTeleportPath(bounds, args.generator);
    else if (args.kind == "walk") {
        auto legs = runtime::parseWalkLegs(args.legs);
        if (!legs)
            return reportError("path", legs.status().withContext("--legs"));
        runtime::PathGeneratorOptions options = args.generator;
        options.legs = std::move(*legs);
        for (auto& leg : options.legs) // world coordinates into the file's frame
            for (glm::dvec3& point : leg)
                point -= runtime::sceneOrigin(**scene);
        path = runtime::makeWalkPath(bounds, options);
    } else
        path = gltfCameraPath(**scene, args);
    if (!path)
        return reportError("path", path.status().withContext(args.kind));
    // Generators fit the path to the bounds in the file's frame; files hold world coordinates.
    if (args.kind != "gltf")
        path = path->translated(runtime::sceneOrigin(**scene));

    if (const Status written = output->commitText(path->toJson()); !written)
        return reportError("path", written);
    std::printf(
            "%s: %s path, %lld frames over %.3g s, %zu keyframes (%s)\n",
            args.output.c_str(),
            args.kind.c_str(),
            static_cast<long long>(path->frameCount()),
            path->endTime() - path->startTime(),
            path->keyframes().size(),
            runtime::pathInterpolationName(path->interpolation()));
    return 0;
}

} // namespace

CommandRunner addPathCommand(CLI::App& app) {
    auto args = std::make_shared<PathArgs>();
    CLI::App* cmd = app.add_subcommand(
            "path",
            "Make a camera path fitted to a scene (JSON, docs/camera-paths.md) for render --path");
    cmd->add_option(
               "kind",
               args->kind,
               "orbit: circle around the scene; flythrough: through its interior; teleports: "
               "random jumps held a few frames; walk: along given legs (--legs), jumping between "
               "them; gltf: through the scene's glTF cameras")
            ->required()
            ->check(CLI::IsMember({"orbit", "flythrough", "teleports", "walk", "gltf"}));
    cmd->add_option("scene", args->scene, "Scene file (.ffs)")->required();
    cmd->add_option("-o,--output", args->output, "Camera path to write (.json)")->required();
    args->framesOption = cmd->add_option(
                                    "--frames",
                                    args->generator.frames,
                                    "Frames in the path (gltf: default one per 1/fps s)")
                                 ->capture_default_str();
    cmd->add_option("--fps", args->generator.fps, "Frames per second")->capture_default_str();
    cmd->add_option("--seed", args->generator.seed, "Random seed (flythrough, teleports)")
            ->capture_default_str();
    cmd->add_option("--teleports", args->generator.teleports, "Number of jumps (teleports)")
            ->capture_default_str();
    cmd->add_option("--fov", args->generator.fovDegrees, "Vertical field of view, degrees")
            ->capture_default_str();
    cmd->add_option(
            "--legs",
            args->legs,
            "walk: polylines in world coordinates, \"x,y,z x,y,z; x,y,z x,y,z\" (legs separated by "
            "';'), e.g. along a street at eye height");
    cmd->add_option("--look-ahead", args->generator.legLookAhead, "walk: how far ahead the camera looks, units")
            ->capture_default_str();
    return [args]() { return runPath(*args); };
}

} // namespace ff::viewer
