// "path" scenarios: popping, flicker and paging along a generated camera path. Every frame of
// the path is rendered once with all geometry (the reference); then each method flies the path
// (resident, or through a cold streaming cache of "cache_mb"), and every frame is compared with
// its reference: PSNR, and the temporal instability of ImageMetrics.h (the approximation's
// frame-to-frame change beyond the reference's). Keys: bench/README.md.

#include "BenchSupport.h"
#include "ScenarioParts.h"

#include <ff/bench/Benchmarks.h>
#include <ff/runtime/CameraOptions.h>
#include <ff/runtime/CameraPathGenerators.h>
#include <ff/runtime/FrameTelemetry.h>
#include <ff/runtime/ImageMetrics.h>
#include <ff/runtime/OffscreenContext.h>
#include <ff/runtime/Percentile.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

namespace ff::bench {

namespace {

struct PathParams {
    SceneSpec scene;
    std::array<int, 2> size = {640, 480};
    PathSpec path;
    int supersample = 1;
    std::vector<MethodSpec> methods;
    /** cacheMb 0: every page resident (memory map); else a cold streaming cache per method. */
    CacheSpec cache = {.cacheMb = 0};
};

/** The path in the scene file's frame (where sessions draw). */
Result<runtime::CameraPath> makePath(const PathSpec& p, const storage::SceneIndex& scene) {
    const runtime::Bounds bounds = runtime::sceneBounds(scene);
    if (p.generator == "flythrough")
        return runtime::makeFlythroughPath(bounds, p.options);
    if (p.generator == "teleports")
        return runtime::makeTeleportPath(bounds, p.options);
    if (p.generator == "walk") {
        runtime::PathGeneratorOptions options = p.options;
        for (auto& leg : options.legs) // world coordinates into the file's frame
            for (glm::dvec3& point : leg)
                point -= runtime::sceneOrigin(scene);
        return runtime::makeWalkPath(bounds, options);
    }
    return runtime::makeOrbitPath(bounds, p.options);
}

/** The session a method draws through: every page mapped, or a cold streaming cache. */
Result<std::unique_ptr<runtime::StreamingSession>> openSession(const PathParams& p, const std::filesystem::path& scenePath) {
    runtime::SessionOptions options;
    options.cacheBytes = static_cast<std::uint64_t>(p.cache.cacheMb) << 20;
    options.ioThreads = static_cast<unsigned>(p.cache.ioThreads);
    return runtime::StreamingSession::open(scenePath, options);
}

/** One build of the scene: the methods that name the same decomposition share it. */
struct BuiltScene {
    std::string decomposition; ///< empty: the scenario's build flags alone
    std::filesystem::path path;
    std::uint64_t nodes = 0;     ///< the build report's, every node of the file
    std::uint64_t leafNodes = 0; ///< prototype nodes without children
};

/** Builds the scene once per decomposition the methods name, in their order. */
Result<std::vector<BuiltScene>> buildScenes(
        const PathParams& p, const Scenario& scenario, const BenchOptions& options, const std::filesystem::path& work) {
    std::vector<BuiltScene> scenes;
    for (const MethodSpec& method : p.methods) {
        if (std::any_of(scenes.begin(), scenes.end(), [&](const BuiltScene& b) { return b.decomposition == method.decomposition; }))
            continue;
        BuiltScene built;
        built.decomposition = method.decomposition;
        const std::string suffix = built.decomposition.empty() ? "" : "-" + built.decomposition;
        built.path = work / (scenario.name + suffix + ".ffs");
        const std::filesystem::path report = work / (scenario.name + suffix + "-build.json");
        std::vector<std::string> flags = {"--report", report.string()};
        if (!built.decomposition.empty())
            flags.insert(flags.end(), {"--decomposition", built.decomposition});
        std::fprintf(stderr, "%s: building the scene%s\n", scenario.name.c_str(),
                     built.decomposition.empty() ? "" : (" (" + built.decomposition + ")").c_str());
        FF_RETURN_IF_ERROR(buildScene(p.scene, flags, built.path, options.selfExe).status().withContext(scenario.where()));
        FF_ASSIGN_OR_RETURN(const nlohmann::json json, readJsonObject(report, "build report"));
        built.nodes = json.value("nodes", std::uint64_t{0});
        built.leafNodes = json.value("leaf_nodes", std::uint64_t{0});
        scenes.push_back(std::move(built));
    }
    return scenes;
}

Status runPath(const PathParams& p, const Scenario& scenario, const BenchOptions& options) {
    ScenarioRun scenarioRun(scenario, options);
    const std::filesystem::path& work = scenarioRun.work();
    FF_ASSIGN_OR_RETURN(const std::vector<BuiltScene> scenes, buildScenes(p, scenario, options, work));
    // Every build holds the same triangles: the reference (all geometry) is drawn from the first.
    const std::filesystem::path& scenePath = scenes.front().path;
    FF_ASSIGN_OR_RETURN(auto context, runtime::OffscreenContext::create());
    // The reference of every frame: all geometry, every page mapped.
    FF_ASSIGN_OR_RETURN(auto referenceSession, runtime::StreamingSession::open(scenePath));
    const runtime::Bounds bounds = runtime::sceneBounds(referenceSession->scene());
    auto path = makePath(p.path, referenceSession->scene());
    if (!path)
        return path.status().withContext(scenario.where() + ": path");
    const std::int64_t frames = path->frameCount();
    const int width = p.size[0];
    const int height = p.size[1];
    auto cameraAt = [&](std::int64_t f) {
        runtime::Camera camera =
                path->sample(path->frameTime(std::clamp<std::int64_t>(f, 0, frames - 1)));
        camera.fitClipPlanes(bounds);
        return camera;
    };

    // ---- the reference of every frame: all geometry, resident ------------------------------
    std::fprintf(
            stderr,
            "%s: %lld reference frames\n",
            scenario.name.c_str(),
            static_cast<long long>(frames));
    std::vector<runtime::Image> references;
    {
        runtime::SelectionOptions full;
        full.method = runtime::Method::Full;
        for (std::int64_t f = 0; f < frames; ++f) {
            FF_ASSIGN_OR_RETURN(
                    runtime::Frame frame,
                    referenceSession->render(frameAt(cameraAt(f), full, width, height, p.supersample)));
            references.push_back(std::move(frame.image));
        }
    }
    referenceSession.reset();

    // The session's telemetry, between the method and the instability of the frame pair.
    std::vector<std::string> perFrameColumns = {"method"};
    for (const std::string& name : runtime::telemetryColumnNames())
        perFrameColumns.push_back(name);
    perFrameColumns.push_back("instability");
    CsvTable perFrame(perFrameColumns);
    CsvTable summary(
            {"method",
             "selection",
             "eps",
             "cube_draw",
             "cube_anisotropy",
             "frames",
             "mean_instability",
             "p95_instability",
             "max_instability",
             "median_psnr",
             "min_psnr",
             "p50_ms",
             "p99_ms",
             "debt_frames",
             "bytes_read",
             // Decompositions (issue 15): the build each method drew, and its node counts.
             "decomposition",
             "scene_nodes",
             "leaf_nodes",
             // Occlusion culling (issue 15): Meißner et al.'s Table 1 per method, means over the path.
             "occlusion",
             "coherence",
             "backend",
             "mean_ms",
             "mean_select_ms",
             "mean_occlusion_ms",
             "mean_draw_ms",
             "mean_triangles",
             "mean_render_rate",
             "mean_queries",
             "mean_queries_waited",
             "mean_nodes_occluded",
             "fps",
             "mean_triangles_occluded"});
    for (const MethodSpec& method : p.methods) {
        std::fprintf(stderr, "%s: method %s\n", scenario.name.c_str(), method.label.c_str());
        const BuiltScene& built = *std::find_if(scenes.begin(), scenes.end(), [&](const BuiltScene& b) {
            return b.decomposition == method.decomposition;
        });
        FF_ASSIGN_OR_RETURN(std::unique_ptr<runtime::StreamingSession> session, openSession(p, built.path));
        runtime::TemporalInstabilityAccumulator accumulator;
        std::vector<double> instability, psnr, frameMs;
        struct Means {
            double select = 0, occlusion = 0, draw = 0, triangles = 0, renderRate = 0, queries = 0,
                   waited = 0, occluded = 0, trianglesOccluded = 0;
        } sums;
        std::uint64_t debtFrames = 0;
        runtime::Image previous;
        for (std::int64_t f = 0; f < frames; ++f) {
            if (session->streams() && p.cache.prefetchFrames > 0)
                session->setPrefetchCamera(cameraAt(f + p.cache.prefetchFrames));
            runtime::FrameContext frameContext = frameAt(cameraAt(f), method.selection, width, height);
            frameContext.occlusion = method.occlusion;
            frameContext.timeSeconds = path->frameTime(f);
            frameContext.budgets.pageInstallsPerFrame = static_cast<std::size_t>(p.cache.uploadsPerFrame);
            FF_ASSIGN_OR_RETURN(
                    runtime::Frame frame,
                    method.oracle ? session->renderOracle(frameContext) : session->render(frameContext));
            runtime::FrameTelemetry telemetry = session->lastFrame();
            const runtime::Image& reference = references[static_cast<std::size_t>(f)];
            FF_ASSIGN_OR_RETURN(
                    const runtime::ColorError color, runtime::colorError(frame.image, reference));
            telemetry.psnrDb = color.psnrSrgb;
            std::string pairCell;
            if (f > 0) {
                FF_ASSIGN_OR_RETURN(
                        const double pair,
                        runtime::temporalInstability(
                                previous,
                                frame.image,
                                references[static_cast<std::size_t>(f - 1)],
                                reference));
                accumulator.add(pair);
                instability.push_back(pair);
                pairCell = formatNumber(pair, 6);
            }
            // As before the streaming session: installing reads, selection and drawing (not the
            // readback or the prefetch walk), so the percentiles stay comparable.
            frameMs.push_back(telemetry.pumpMs + frame.stats.totalMs);
            psnr.push_back(color.psnrSrgb);
            sums.select += frame.stats.selectMs;
            sums.occlusion += frame.stats.occlusionMs;
            sums.draw += frame.stats.drawMs;
            sums.triangles += static_cast<double>(frame.stats.trianglesDrawn);
            sums.renderRate += telemetry.renderRatePercent;
            sums.queries += static_cast<double>(frame.stats.occlusionQueries);
            sums.waited += static_cast<double>(frame.stats.queriesWaited);
            sums.occluded += static_cast<double>(frame.stats.nodesOccluded);
            sums.trianglesOccluded += static_cast<double>(frame.stats.trianglesOccluded);
            debtFrames += frame.stats.nodesDeferred > 0 ? 1 : 0;
            std::vector<std::string> row = {method.label};
            for (std::string& cell : runtime::telemetryCsvCells(telemetry))
                row.push_back(std::move(cell));
            row.push_back(pairCell);
            perFrame.addRow(std::move(row));
            previous = std::move(frame.image);
        }
        const runtime::TemporalInstability total = accumulator.result();
        const auto n = static_cast<double>(frames);
        const auto mean = [](const std::vector<double>& v) {
            double sum = 0.0;
            for (const double x : v)
                sum += x;
            return v.empty() ? 0.0 : sum / static_cast<double>(v.size());
        };
        summary.addRow(
                {method.label,
                 method.methodName(),
                 formatNumber(method.selection.epsilonPixels, 3),
                 method.cubeDrawName(),
                 formatNumber(method.selection.maxCubeAnisotropy),
                 std::to_string(frames),
                 formatNumber(total.mean, 6),
                 formatNumber(runtime::percentile(instability, 0.95), 6),
                 formatNumber(total.maxFrame, 6),
                 formatNumber(runtime::percentile(psnr, 0.5), 3), // a median: identical frames score inf
                 formatNumber(*std::min_element(psnr.begin(), psnr.end()), 3),
                 formatNumber(runtime::percentile(frameMs, 0.50), 3),
                 formatNumber(runtime::percentile(frameMs, 0.99), 3),
                 std::to_string(debtFrames),
                 std::to_string(session->totals().bytesRead),
                 built.decomposition.empty() ? "as built" : built.decomposition,
                 std::to_string(built.nodes),
                 std::to_string(built.leafNodes),
                 method.oracle ? "oracle" : method.occlusion.enabled ? "on" : "off",
                 method.occlusion.coherent ? "on" : "off",
                 runtime::occlusionBackendName(method.occlusion.backend),
                 formatNumber(mean(frameMs), 3),
                 formatNumber(sums.select / n, 3),
                 formatNumber(sums.occlusion / n, 3),
                 formatNumber(sums.draw / n, 3),
                 formatNumber(sums.triangles / n, 0),
                 formatNumber(sums.renderRate / n, 4),
                 formatNumber(sums.queries / n, 1),
                 formatNumber(sums.waited / n, 1),
                 formatNumber(sums.occluded / n, 1),
                 formatNumber(1000.0 / std::max(mean(frameMs), 1e-9), 2),
                 formatNumber(sums.trianglesOccluded / n, 0)});
    }

    const std::filesystem::path csv = options.outDir / (scenario.name + ".csv");
    FF_RETURN_IF_ERROR(perFrame.write(csv));
    FF_RETURN_IF_ERROR(summary.write(options.outDir / (scenario.name + "-summary.csv")));
    std::ostringstream md;
    md << "Command: `" << options.command << "`\n\n"
       << "Scene: "
       << (p.scene.gltf.empty() ? "`--generate " + p.scene.generate + "`"
                                : "`" + p.scene.gltf + "`")
       << (scenes.size() > 1 ? ", built once per decomposition the methods name" : "")
       << ". Path: `farfield path " << p.path.generator << "`, " << frames << " frames at " << width
       << "x" << height << ". Pages: "
       << (p.cache.cacheMb == 0
                   ? std::string("all resident")
                   : "a cold " + std::to_string(p.cache.cacheMb) + " MiB streaming cache per method")
       << ". Reference: method full, " << p.supersample << "x" << p.supersample
       << " supersampled, every frame. "
       << "Instability: the mean over pixels of the approximation's frame-to-frame change in "
          "linear luminance "
       << "beyond the reference's own (docs/metrics.md); per frame in `" << scenario.name
       << ".csv`.\n\n"
       << summary.markdown() << "\n![instability and PSNR per frame](" << scenario.name
       << ".png)\n";
    if (p.cache.cacheMb > 0)
        md << "\n![PSNR against bytes read](" << scenario.name << "-bytes.png)\n";
    return scenarioRun.finish("path", csv, md.str());
}

} // namespace

Result<BenchRun> preparePath(const Scenario& scenario) {
    PathParams p;
    ScenarioReader reader = readScenario(scenario);
    p.scene = readSceneSpec(reader);
    p.size = reader.size("size", p.size);
    if (!reader.has("path"))
        reader.fail("path", "missing: e.g. {\"generator\": \"orbit\", \"frames\": 60}");
    // At least 2 frames: instability compares consecutive frames.
    p.path = readPathSpec(reader, p.path, 2);
    p.supersample = readReferenceSupersample(reader, p.supersample);
    p.methods = readMethods(reader);
    p.cache = readCacheSpec(reader, p.cache, 0);
    FF_RETURN_IF_ERROR(reader.finish());
    return BenchRun(
            [p, scenario](const BenchOptions& options) { return runPath(p, scenario, options); });
}

} // namespace ff::bench
