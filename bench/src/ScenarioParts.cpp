#include "ScenarioParts.h"

#include "BenchSupport.h"

#include <cmath>
#include <optional>
#include <set>

namespace ff::bench {

SceneSpec readSceneSpec(ScenarioReader& reader) {
    SceneSpec spec;
    if (!reader.has("scene")) {
        reader.fail("scene", "missing: {\"gltf\": FILE} or {\"generate\": \"forest:trees=1\"}");
        return spec;
    }
    ScenarioReader scene = reader.object("scene");
    spec.gltf = scene.string("gltf", "");
    spec.generate = scene.string("generate", "");
    if (spec.gltf.empty() == spec.generate.empty())
        scene.fail("", "give exactly one of \"gltf\" (a file) and \"generate\" (a generator spec)");
    if (auto expanded = expandShared(spec.gltf))
        spec.gltf = *expanded;
    else
        scene.fail("gltf", expanded.status().message());
    spec.buildFlags = readBuildFlags(reader);
    return spec;
}

std::vector<std::string> readBuildFlags(ScenarioReader& reader) {
    std::vector<std::string> flags;
    for (const std::string& flag : reader.strings("build", {})) {
        if (auto expanded = expandShared(flag))
            flags.push_back(*expanded);
        else
            reader.fail("build", expanded.status().message());
    }
    return flags;
}

std::string buildFlagsNote(const std::vector<std::string>& flags) {
    if (flags.empty())
        return "";
    std::string joined;
    for (const std::string& flag : flags)
        joined += (joined.empty() ? "" : " ") + flag;
    return " Every scene is built with `" + joined + "`.";
}

Result<ChildRun> buildScene(
        const SceneSpec& scene,
        const std::vector<std::string>& extraFlags,
        const std::filesystem::path& output,
        const std::string& selfExe) {
    std::vector<std::string> argv = {selfExe, "build", "-q", "-o", output.string()};
    if (!scene.gltf.empty())
        argv.push_back(scene.gltf);
    else
        argv.insert(argv.end(), {"--generate", scene.generate});
    argv.insert(argv.end(), scene.buildFlags.begin(), scene.buildFlags.end());
    argv.insert(argv.end(), extraFlags.begin(), extraFlags.end());
    return runChild(argv);
}

std::vector<std::string> PathSpec::commandArgs(
        const std::filesystem::path& scene, const std::filesystem::path& output) const {
    std::vector<std::string> args = {"path", generator, scene.string(), "-o", output.string(),
                                     "--frames", std::to_string(options.frames), "--fps",
                                     sweepValueText(options.fps), "--seed", std::to_string(options.seed),
                                     "--fov", sweepValueText(options.fovDegrees)};
    if (generator == "teleports")
        args.insert(args.end(), {"--teleports", std::to_string(options.teleports)});
    if (generator == "walk")
        args.insert(args.end(), {"--legs", runtime::formatWalkLegs(options.legs), "--look-ahead",
                                 sweepValueText(options.legLookAhead)});
    return args;
}

CacheSpec readCacheSpec(ScenarioReader& reader, CacheSpec fallback, std::int64_t minCacheMb) {
    CacheSpec c = fallback;
    c.cacheMb = reader.integer("cache_mb", c.cacheMb);
    c.ioThreads = reader.integer("io_threads", c.ioThreads);
    c.uploadsPerFrame = reader.integer("uploads_per_frame", c.uploadsPerFrame);
    c.prefetchFrames = reader.integer("prefetch_frames", c.prefetchFrames);
    if (c.cacheMb < minCacheMb || c.ioThreads < 1 || c.uploadsPerFrame < 1 || c.prefetchFrames < 0)
        reader.fail("", "cache_mb must be >= " + std::to_string(minCacheMb) +
                                ", io_threads and uploads_per_frame >= 1, prefetch_frames >= 0");
    return c;
}

PathSpec readPathSpec(ScenarioReader& reader, PathSpec fallback, std::int64_t minFrames) {
    PathSpec p = std::move(fallback);
    ScenarioReader path = reader.object("path");
    p.generator = path.choice("generator", p.generator, {"orbit", "flythrough", "teleports", "walk"});
    if (const nlohmann::json* legs = path.raw("legs")) {
        const auto isPoint = [](const nlohmann::json& v) {
            return v.is_array() && v.size() == 3 && v[0].is_number() && v[1].is_number() && v[2].is_number();
        };
        p.options.legs.clear();
        for (const nlohmann::json& leg : legs->is_array() ? *legs : nlohmann::json::array()) {
            std::vector<glm::dvec3> points;
            for (const nlohmann::json& point : leg.is_array() ? leg : nlohmann::json::array())
                if (isPoint(point))
                    points.emplace_back(point[0].get<double>(), point[1].get<double>(), point[2].get<double>());
            if (points.size() < 2 || points.size() != leg.size())
                path.fail("legs", "expected [[[x,y,z], [x,y,z], ...], ...]: legs of two points or more");
            p.options.legs.push_back(std::move(points));
        }
    }
    p.options.legLookAhead = path.number("look_ahead", p.options.legLookAhead);
    if (p.generator == "walk" && p.options.legs.empty())
        path.fail("legs", "a walk needs its legs, e.g. [[[0,1.7,100], [0,1.7,-100]]]");
    p.options.frames = path.integer("frames", p.options.frames);
    p.options.fps = path.number("fps", p.options.fps);
    const std::int64_t seed = path.integer("seed", static_cast<std::int64_t>(p.options.seed));
    p.options.seed = static_cast<std::uint64_t>(std::max<std::int64_t>(0, seed));
    p.options.teleports = path.integer("teleports", p.options.teleports);
    p.options.fovDegrees = path.number("fov", p.options.fovDegrees);
    if (p.options.frames < minFrames)
        path.fail("frames", "must be >= " + std::to_string(minFrames));
    if (seed < 0)
        path.fail("seed", "must be >= 0");
    if (!(p.options.fps > 0.0))
        path.fail("fps", "must be positive");
    if (!(p.options.fovDegrees > 0.0 && p.options.fovDegrees < 179.0))
        path.fail("fov", "must be between 0 and 179 degrees");
    if (p.generator == "teleports" &&
        (p.options.teleports < 1 || p.options.frames < 2 * p.options.teleports))
        path.fail("teleports", "needs teleports >= 1 and frames >= 2 * teleports");
    return p;
}

const char* MethodSpec::methodName() const noexcept {
    return runtime::methodName(selection.method);
}

const char* MethodSpec::cubeDrawName() const noexcept {
    return runtime::cubeStyleName(selection.cubeStyle);
}

Status setMethodKey(MethodSpec& method, const std::string& key, const nlohmann::json& value) {
    if (key == "eps") {
        if (!value.is_number() || !(value.get<double>() >= 0.0) ||
            !std::isfinite(value.get<double>()))
            return Status(
                    ErrorCode::InvalidArgument,
                    "eps: expected a number >= 0 (pixels), got " + value.dump());
        method.selection.epsilonPixels = value.get<float>();
        return Status::ok();
    }
    if (key == "cube_draw") {
        const std::optional<runtime::CubeStyle> style =
                runtime::parseCubeStyle(value.is_string() ? value.get<std::string>() : std::string());
        if (style)
            method.selection.cubeStyle = *style;
        else
            return Status(
                    ErrorCode::InvalidArgument,
                    "cube_draw: expected \"faces\", \"points\" or \"auto\", got " + value.dump());
        return Status::ok();
    }
    if (key == "cube_anisotropy") {
        if (!value.is_number() || !(value.get<double>() >= 0.0 && value.get<double>() <= 1.0))
            return Status(
                    ErrorCode::InvalidArgument,
                    "cube_anisotropy: expected a number in [0, 1] (1 accepts every cube), got " + value.dump());
        method.selection.maxCubeAnisotropy = value.get<float>();
        return Status::ok();
    }
    if (key == "representation") {
        const std::optional<runtime::Representation> representation =
                value.is_string() ? runtime::parseRepresentation(value.get<std::string>()) : std::nullopt;
        if (!representation)
            return Status(ErrorCode::InvalidArgument,
                          "representation: expected \"auto\", \"cube\", \"simplified\" or \"splats\", got " +
                                  value.dump());
        method.selection.representation = *representation;
        return Status::ok();
    }
    if (key == "splat_size") {
        if (!value.is_number() || !(value.get<double>() >= 1.0 && value.get<double>() <= 3.0))
            return Status(
                    ErrorCode::InvalidArgument,
                    "splat_size: expected a number of pixels in [1, 3], got " + value.dump());
        method.selection.splats.pixels = value.get<float>();
        return Status::ok();
    }
    if (key == "splat_shape") {
        if (!value.is_string() || (value.get<std::string>() != "round" && value.get<std::string>() != "square"))
            return Status(
                    ErrorCode::InvalidArgument,
                    "splat_shape: expected \"round\" or \"square\", got " + value.dump());
        method.selection.splats.round = value.get<std::string>() == "round";
        return Status::ok();
    }
    if (key == "occlusion" || key == "coherence" || key == "oracle" || key == "cube_occluders") {
        if (!value.is_boolean())
            return Status(ErrorCode::InvalidArgument, key + ": expected true or false, got " + value.dump());
        bool& flag = key == "occlusion"   ? method.occlusion.enabled
                     : key == "coherence" ? method.occlusion.coherent
                     : key == "oracle"    ? method.oracle
                                          : method.occlusion.cubesOcclude;
        flag = value.get<bool>();
        return Status::ok();
    }
    if (key == "occlusion_backend") {
        const std::optional<runtime::OcclusionBackend> backend =
                value.is_string() ? runtime::parseOcclusionBackend(value.get<std::string>()) : std::nullopt;
        if (!backend)
            return Status(ErrorCode::InvalidArgument,
                          "occlusion_backend: expected \"queries\" or \"hzb\", got " + value.dump());
        method.occlusion.backend = *backend;
        return Status::ok();
    }
    if (key == "opacity_threshold") {
        if (!value.is_number() || !(value.get<double>() >= 0.0 && value.get<double>() <= 0.5))
            return Status(
                    ErrorCode::InvalidArgument,
                    "opacity_threshold: expected a number in [0, 0.5] (the light an occluding pixel may let through), got " +
                            value.dump());
        method.occlusion.opacityThreshold = value.get<float>();
        return Status::ok();
    }
    if (key == "occlusion_min_hidden") {
        if (!value.is_number() || !(value.get<double>() >= 0.0 && value.get<double>() <= 1.0))
            return Status(
                    ErrorCode::InvalidArgument,
                    "occlusion_min_hidden: expected a share in [0, 1] (0: every frame tested), got " + value.dump());
        method.occlusion.minHiddenShare = value.get<float>();
        return Status::ok();
    }
    return Status(
            ErrorCode::InvalidArgument,
            "\"" + key +
                    "\" is not a method key a sweep can vary (eps, cube_draw, cube_anisotropy, representation, splat_size, "
                    "splat_shape, occlusion, coherence, oracle, occlusion_backend, cube_occluders, opacity_threshold, "
                    "occlusion_min_hidden)");
}

std::vector<MethodSpec> readMethods(ScenarioReader& reader) {
    std::vector<MethodSpec> methods;
    if (!reader.has("methods")) {
        reader.fail(
                "methods",
                "missing: e.g. [{\"label\": \"full\", \"method\": \"full\"}, {\"label\": \"eps1\", "
                "\"eps\": 1}]");
        return methods;
    }
    std::set<std::string> labels;
    for (ScenarioReader& m : reader.objects("methods")) {
        MethodSpec method;
        const std::string kind = m.choice("method", "hierarchical", {"hierarchical", "full"});
        method.selection.method = runtime::parseMethod(kind).value_or(runtime::Method::Hierarchical); // choice() checked it
        for (const char* key : kSweepableMethodKeys)
            if (const nlohmann::json* value = m.raw(key))
                if (Status status = setMethodKey(method, key, *value); !status)
                    m.fail("", status.message());
        method.decomposition = m.choice("decomposition", "", {"", "octree", "dbvd", "phbvo", "balanced", "orsd"});
        method.label = m.string(
                "label",
                kind == "full" ? "full" : "eps" + sweepValueText(method.selection.epsilonPixels));
        if (!labels.insert(method.label).second)
            m.fail("label",
                   "\"" + method.label +
                           "\" is used by two methods; labels name rows and chart series");
        methods.push_back(std::move(method));
    }
    if (methods.empty())
        reader.fail("methods", "needs at least one method");
    return methods;
}

std::string sweepValueText(const nlohmann::json& value) {
    return value.is_string() ? value.get<std::string>() : value.dump();
}

int readReferenceSupersample(ScenarioReader& reader, int fallback) {
    ScenarioReader reference = reader.object("reference");
    const std::int64_t supersample = reference.integer("supersample", fallback);
    if (supersample < 1 || supersample > 16) {
        reference.fail("supersample", "must be 1..16");
        return fallback;
    }
    return static_cast<int>(supersample);
}

} // namespace ff::bench
