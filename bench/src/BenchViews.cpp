// "views" scenarios: speed against accuracy at fixed views. For every view, the full reference
// (supersampled) once, then every method (and every sweep value of the hierarchical ones) timed
// as the median of --frames frames after a warm-up and compared with the reference: PSNR, SSIM,
// holes and over-coverage. Keys: bench/README.md.

#include "BenchSupport.h"
#include "ScenarioParts.h"

#include <ff/bench/Benchmarks.h>
#include <ff/runtime/CameraOptions.h>
#include <ff/runtime/ImageMetrics.h>
#include <ff/runtime/OffscreenContext.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace ff::bench {

namespace {

/** A view: what the same keys mean as `farfield render` flags (runtime::CameraOptions). */
struct ViewSpec {
    std::string label;
    runtime::CameraOptions camera;
};

/** "sweep": one parameter over values; a method key or "build:--FLAG". */
struct SweepSpec {
    std::string parameter; ///< empty: no sweep
    std::vector<nlohmann::json> values;

    bool active() const noexcept { return !parameter.empty(); }
    bool rebuilds() const noexcept { return parameter.rfind("build:", 0) == 0; }
    std::string buildFlag() const { return parameter.substr(6); }
};

struct ViewsParams {
    SceneSpec scene;
    std::array<int, 2> size = {640, 480};
    std::vector<ViewSpec> views;
    int supersample = 4;
    std::vector<MethodSpec> methods;
    SweepSpec sweep;
};

constexpr const char* kBuildPrefix = "build:";

std::string vec3Text(const nlohmann::json& v) {
    char text[96];
    std::snprintf(
            text,
            sizeof(text),
            "%.9g,%.9g,%.9g",
            v[0].get<double>(),
            v[1].get<double>(),
            v[2].get<double>());
    return text;
}

bool isVec3(const nlohmann::json& v) {
    return v.is_array() && v.size() == 3 && v[0].is_number() && v[1].is_number() &&
           v[2].is_number();
}

/** "camera": {"position", "target", "up", "fov"} or "gltf:N", onto the render flags. */
void readCamera(ScenarioReader& view, runtime::CameraOptions& camera) {
    const nlohmann::json* value = view.raw("camera");
    if (value->is_string()) {
        camera.camera = value->get<std::string>();
        return;
    }
    if (!value->is_object()) {
        view.fail("camera", "expected {\"position\": [x,y,z], \"target\": [x,y,z]} or \"gltf:N\"");
        return;
    }
    ScenarioReader c = view.object("camera");
    for (const char* key : {"position", "target", "up"}) {
        const nlohmann::json* v = c.raw(key);
        if (v && !isVec3(*v))
            c.fail(key, "expected [x, y, z]");
        else if (v)
            (key[0] == 'p' ? camera.eye : key[0] == 't' ? camera.target : camera.up) = vec3Text(*v);
    }
    if (camera.eye.empty() || camera.target.empty())
        c.fail("", "needs \"position\" and \"target\"");
    if (c.has("fov")) {
        if (view.has("fov"))
            view.fail("fov", "given twice (here and in \"camera\")");
        camera.fovDegrees = static_cast<float>(c.number("fov", camera.fovDegrees));
    }
}

std::vector<ViewSpec> readViews(ScenarioReader& reader) {
    std::vector<ViewSpec> views;
    std::set<std::string> labels;
    for (ScenarioReader& v : reader.objects("views")) {
        ViewSpec view;
        view.label = v.string("label", "view" + std::to_string(views.size()));
        runtime::CameraOptions& camera = view.camera;
        camera.fovDegrees = static_cast<float>(v.number("fov", camera.fovDegrees));
        if (v.has("camera")) {
            for (const char* key : {"distance", "azimuth", "elevation"})
                if (v.has(key))
                    v.fail(key, "an orbit key does not go with \"camera\"");
            readCamera(v, camera);
        } else {
            camera.distance = static_cast<float>(v.number("distance", camera.distance));
            camera.azimuth = static_cast<float>(v.number("azimuth", camera.azimuth));
            camera.elevation = static_cast<float>(v.number("elevation", camera.elevation));
            if (!(camera.distance > 0.0f))
                v.fail("distance", "must be positive (scene radii)");
        }
        if (!(camera.fovDegrees > 0.0f && camera.fovDegrees < 179.0f))
            v.fail("fov", "must be between 0 and 179 degrees");
        if (!labels.insert(view.label).second)
            v.fail("label", "\"" + view.label + "\" is used by two views");
        views.push_back(std::move(view));
    }
    if (views.empty())
        reader.fail(
                "views",
                "missing or empty: e.g. [{\"label\": \"d6\", \"distance\": 6, \"azimuth\": 45}]");
    return views;
}

SweepSpec readSweep(ScenarioReader& reader, const std::vector<MethodSpec>& methods) {
    SweepSpec sweep;
    if (!reader.has("sweep"))
        return sweep;
    ScenarioReader s = reader.object("sweep");
    sweep.parameter = s.string("parameter", "");
    const nlohmann::json* values = s.raw("values");
    if (!values || !values->is_array() || values->empty()) {
        s.fail("values", "expected a non-empty array of values");
        return sweep;
    }
    sweep.values.assign(values->begin(), values->end());
    for (const nlohmann::json& value : sweep.values)
        if (!value.is_number() && !value.is_string())
            s.fail("values", "expected numbers or strings, got " + value.dump());
    if (sweep.rebuilds()) {
        if (sweep.buildFlag().empty() || sweep.buildFlag()[0] != '-')
            s.fail("parameter",
                   "\"" + sweep.parameter +
                           "\": expected build:--FLAG, e.g. build:--bake-resolution");
        return sweep;
    }
    const bool sweepable = std::any_of(
            std::begin(kSweepableMethodKeys), std::end(kSweepableMethodKeys), [&](const char* key) {
                return sweep.parameter == key;
            });
    if (!sweepable) {
        s.fail("parameter",
               "\"" + sweep.parameter +
                       "\" is neither a method key a sweep can vary (eps, cube_draw, cube_anisotropy, representation, ...) nor " +
                       kBuildPrefix + "--FLAG");
        return sweep;
    }
    for (const nlohmann::json& value : sweep.values) {
        MethodSpec probe;
        if (Status status = setMethodKey(probe, sweep.parameter, value); !status)
            s.fail("values", status.message());
    }
    if (std::all_of(methods.begin(), methods.end(), [](const MethodSpec& m) { return m.isFull(); }))
        s.fail("parameter",
               "a method-key sweep varies the hierarchical methods, and there are none");
    return sweep;
}

std::uint64_t coveredPixels(const runtime::Image& image) {
    std::uint64_t covered = 0;
    for (std::size_t i = 3; i < image.rgba.size(); i += 4)
        covered += static_cast<float>(image.rgba[i]) / 255.0f >= runtime::kDefaultCoverageThreshold
                           ? 1u
                           : 0u;
    return covered;
}

double fraction(std::uint64_t count, std::uint64_t of) {
    if (of == 0)
        return count == 0 ? 0.0 : std::numeric_limits<double>::infinity();
    return static_cast<double>(count) / static_cast<double>(of);
}

std::string fileSafe(const std::string& text) {
    std::string safe = text;
    for (char& c : safe)
        if (!std::isalnum(static_cast<unsigned char>(c)) && c != '.' && c != '-' && c != '_')
            c = '_';
    return safe;
}

std::string describeScene(const SceneSpec& scene) {
    std::string text =
            scene.gltf.empty() ? "`--generate " + scene.generate + "`" : "`" + scene.gltf + "`";
    if (!scene.buildFlags.empty()) {
        text += " built with `";
        for (std::size_t i = 0; i < scene.buildFlags.size(); ++i)
            text += (i ? " " : "") + scene.buildFlags[i];
        text += "`";
    }
    return text;
}

Status runViews(const ViewsParams& p, const Scenario& scenario, const BenchOptions& options) {
    ScenarioRun scenarioRun(scenario, options);
    const std::filesystem::path& work = scenarioRun.work();
    FF_ASSIGN_OR_RETURN(auto context, runtime::OffscreenContext::create());
    const int width = p.size[0];
    const int height = p.size[1];
    CsvTable table(
            {"view",
             "method",
             "selection",
             "eps",
             "cube_draw",
             "cube_anisotropy",
             "sweep_parameter",
             "sweep_value",
             "width",
             "height",
             "frame_ms",
             "select_ms",
             "draw_ms",
             "triangles",
             "cubes",
             "psnr_srgb",
             "ssim",
             "holes_fraction",
             "over_coverage_fraction",
             "reference_covered_pixels",
             "scene_triangles",
             "scene_file_bytes",
             "representation",
             "stand_ins",
             "splat_sets",
             "splats",
             "splat_size"});
    // A build sweep rebuilds the scene per value; otherwise one build and no value here.
    const std::vector<std::optional<nlohmann::json>> builds = [&] {
        std::vector<std::optional<nlohmann::json>> list;
        if (p.sweep.rebuilds())
            list.assign(p.sweep.values.begin(), p.sweep.values.end());
        else
            list.emplace_back();
        return list;
    }();
    std::string sceneSummary;
    for (const std::optional<nlohmann::json>& buildValue : builds) {
        const std::string buildText = buildValue ? sweepValueText(*buildValue) : "";
        const std::filesystem::path scenePath =
                work / (scenario.name + (buildValue ? "-" + fileSafe(buildText) : "") + ".ffs");
        std::fprintf(
                stderr,
                "%s: building the scene%s\n",
                scenario.name.c_str(),
                buildValue ? (" with " + p.sweep.buildFlag() + " " + buildText).c_str() : "");
        std::vector<std::string> extraFlags;
        if (buildValue)
            extraFlags = {p.sweep.buildFlag(), buildText};
        FF_RETURN_IF_ERROR(buildScene(p.scene, extraFlags, scenePath, options.selfExe)
                                   .status()
                                   .withContext(scenario.where()));
        FF_ASSIGN_OR_RETURN(auto session, runtime::StreamingSession::open(scenePath));
        const storage::SceneIndex* file = &session->scene();
        const std::string sceneTriangles = std::to_string(file->header().instancedTriangles);
        const std::string sceneBytes = std::to_string(std::filesystem::file_size(scenePath));
        if (sceneSummary.empty())
            sceneSummary = sceneTriangles + " triangles, " + sceneBytes + " bytes";

        for (const ViewSpec& view : p.views) {
            auto camera = view.camera.resolve(*file);
            if (!camera)
                return camera.status().withContext(scenario.where() + ": view " + view.label);
            std::fprintf(stderr, "%s: view %s\n", scenario.name.c_str(), view.label.c_str());
            runtime::SelectionOptions full;
            full.method = runtime::Method::Full;
            FF_ASSIGN_OR_RETURN(
                    const runtime::Frame reference,
                    session->render(frameAt(*camera, full, width, height, p.supersample)));
            const std::uint64_t covered = coveredPixels(reference.image);

            for (const MethodSpec& method : p.methods) {
                // A method-key sweep varies the hierarchical methods; full runs once.
                std::vector<std::optional<nlohmann::json>> settings(1);
                if (p.sweep.active() && !p.sweep.rebuilds() && !method.isFull())
                    settings.assign(p.sweep.values.begin(), p.sweep.values.end());
                for (const std::optional<nlohmann::json>& setting : settings) {
                    MethodSpec m = method;
                    if (setting)
                        FF_RETURN_IF_ERROR(setMethodKey(m, p.sweep.parameter, *setting));
                    runtime::FrameContext frameContext = frameAt(*camera, m.selection, width, height);
                    frameContext.occlusion = m.occlusion;
                    FF_ASSIGN_OR_RETURN(
                            const runtime::Frame frame,
                            timeFrames(*session, frameContext, 1, options.timedFrames));
                    FF_ASSIGN_OR_RETURN(
                            const runtime::ColorError color,
                            runtime::colorError(frame.image, reference.image));
                    FF_ASSIGN_OR_RETURN(
                            const double ssim, runtime::ssim(frame.image, reference.image));
                    FF_ASSIGN_OR_RETURN(
                            const runtime::CoverageError coverage,
                            runtime::coverageError(frame.image, reference.image));
                    const bool swept = setting.has_value() || buildValue.has_value();
                    table.addRow(
                            {view.label,
                             m.label,
                             m.methodName(),
                             formatNumber(m.selection.epsilonPixels, 3),
                             m.cubeDrawName(),
                             formatNumber(m.selection.maxCubeAnisotropy),
                             swept ? p.sweep.parameter : "",
                             setting ? sweepValueText(*setting) : buildText,
                             std::to_string(width),
                             std::to_string(height),
                             formatNumber(frame.stats.totalMs, 3),
                             formatNumber(frame.stats.selectMs, 3),
                             formatNumber(frame.stats.drawMs, 3),
                             std::to_string(frame.stats.trianglesDrawn),
                             std::to_string(frame.stats.cubesDrawn),
                             formatNumber(color.psnrSrgb, 3),
                             formatNumber(ssim, 4),
                             formatNumber(fraction(coverage.holes, covered), 5),
                             formatNumber(fraction(coverage.overCoverage, covered), 5),
                             std::to_string(covered),
                             sceneTriangles,
                             sceneBytes,
                             runtime::representationName(m.selection.representation),
                             std::to_string(frame.stats.standInsDrawn),
                             std::to_string(frame.stats.splatSetsDrawn),
                             std::to_string(frame.stats.splatsDrawn),
                             formatNumber(m.selection.splats.pixels, 3)});
                }
            }
        }
        session.reset();
        if (options.workDir.empty())
            std::filesystem::remove(scenePath);
    }

    const std::filesystem::path csv = options.outDir / (scenario.name + ".csv");
    FF_RETURN_IF_ERROR(table.write(csv));
    std::ostringstream md;
    md << "Command: `" << options.command << "`\n\n"
       << "Scene: " << describeScene(p.scene) << " (" << sceneSummary << "). Image " << width << "x"
       << height << "; reference: method full, " << p.supersample << "x" << p.supersample
       << " supersampled, once per view" << (p.sweep.rebuilds() ? " and build" : "")
       << ". Times: median of " << options.timedFrames
       << " frames after one warm-up (selection + drawing until glFinish). holes_fraction and "
       << "over_coverage_fraction are relative to the pixels the reference covers (alpha >= "
          "1/2).\n\n"
       << table.markdown() << "\n![error against frame time](" << scenario.name << ".png)\n";
    if (p.sweep.active())
        md << "\n![error against " << p.sweep.parameter << "](" << scenario.name << "-sweep.png)\n";
    return scenarioRun.finish("views", csv, md.str());
}

} // namespace

Result<BenchRun> prepareViews(const Scenario& scenario) {
    ViewsParams p;
    ScenarioReader reader = readScenario(scenario);
    p.scene = readSceneSpec(reader);
    p.size = reader.size("size", p.size);
    p.views = readViews(reader);
    p.supersample = readReferenceSupersample(reader, p.supersample);
    p.methods = readMethods(reader);
    p.sweep = readSweep(reader, p.methods);
    FF_RETURN_IF_ERROR(reader.finish());
    return BenchRun(
            [p, scenario](const BenchOptions& options) { return runViews(p, scenario, options); });
}

} // namespace ff::bench
