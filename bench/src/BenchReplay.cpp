// "replay" scenarios: the paging-behaviour test as a benchmark. One scene is built by a child
// `farfield build` (its time and peak RSS measured), a camera path is fitted to it, and a child
// `farfield replay` flies the path through a cold cache of "cache_mb": per-frame telemetry (the
// CSV), the replay summary, both processes' peak memory. It is how a scene larger than RAM is
// measured (build with --memory-budget, replay with a cache far smaller than the file), so the
// scene file is removed as soon as the replay is done. Keys: bench/README.md.

#include "BenchSupport.h"
#include "ScenarioParts.h"

#include <ff/bench/Benchmarks.h>
#include <ff/runtime/Units.h>

#include <nlohmann/json.hpp>

#include <cstdio>

namespace ff::bench {

namespace {

struct ReplayParams {
    SceneSpec scene;
    PathSpec path = {.generator = "flythrough", .options = {}};
    std::array<int, 2> size = {640, 480};
    CacheSpec cache;
};

std::string joined(const std::vector<std::string>& words) {
    std::string text;
    for (const std::string& word : words)
        text += (text.empty() ? "" : " ") + word;
    return text;
}

std::string bytesCell(const nlohmann::json& object, const char* key) {
    return runtime::formatBytes(object.value(key, std::uint64_t{0}));
}

Status runReplay(const ReplayParams& p, const Scenario& scenario, const BenchOptions& options) {
    ScenarioRun scenarioRun(scenario, options);
    const std::filesystem::path& work = scenarioRun.work();
    const std::string& name = scenario.name;
    const std::filesystem::path scene = work / (name + ".ffs");
    const std::filesystem::path report = work / (name + "-build.json");
    const std::filesystem::path path = work / (name + "-path.json");
    const std::filesystem::path frames = options.outDir / (name + ".csv");
    const std::filesystem::path summaryPath = options.outDir / (name + "-summary.json");
    // The scene may be larger than the disk can hold twice: never leave it behind.
    struct SceneGuard {
        std::filesystem::path path;
        ~SceneGuard() {
            std::error_code ec;
            std::filesystem::remove(path, ec);
        }
    } guard{scene};

    std::fprintf(
            stderr,
            "%s: building %s\n",
            name.c_str(),
            p.scene.gltf.empty() ? p.scene.generate.c_str() : p.scene.gltf.c_str());
    FF_ASSIGN_OR_RETURN(
            const ChildRun build,
            buildScene(p.scene, {"--report", report.string()}, scene, options.selfExe));
    FF_ASSIGN_OR_RETURN(const nlohmann::json built, readJsonObject(report, "build report"));

    std::vector<std::string> pathArgs = p.path.commandArgs(scene, path);
    pathArgs.insert(pathArgs.begin(), options.selfExe);
    FF_RETURN_IF_ERROR(runChild(pathArgs).status());

    std::fprintf(
            stderr,
            "%s: replaying %lld frames through a %lld MiB cache\n",
            name.c_str(),
            static_cast<long long>(p.path.options.frames),
            static_cast<long long>(p.cache.cacheMb));
    FF_ASSIGN_OR_RETURN(
            const ChildRun replay,
            runChild(
                    {options.selfExe,
                     "replay",
                     scene.string(),
                     path.string(),
                     "--cache-mb",
                     std::to_string(p.cache.cacheMb),
                     "--size",
                     std::to_string(p.size[0]) + "x" + std::to_string(p.size[1]),
                     "--io-threads",
                     std::to_string(p.cache.ioThreads),
                     "--uploads-per-frame",
                     std::to_string(p.cache.uploadsPerFrame),
                     "--prefetch-frames",
                     std::to_string(p.cache.prefetchFrames),
                     "--csv",
                     frames.string(),
                     "--summary",
                     summaryPath.string()}));
    FF_ASSIGN_OR_RETURN(const nlohmann::json summary, readJsonObject(summaryPath, "replay summary"));

    const nlohmann::json& bytes = built["bytes"];
    CsvTable buildTable({"triangles", "file", "spill", "memory_budget", "seconds", "peak_rss"});
    buildTable.addRow(
            {std::to_string(built.value("instanced_triangles", std::uint64_t{0})),
             bytesCell(bytes, "file"),
             bytesCell(bytes, "spill"),
             bytesCell(built, "memory_budget_bytes"),
             formatNumber(build.seconds),
             runtime::formatBytes(build.peakRssBytes)});
    CsvTable replayTable(
            {"frames",
             "p50_ms",
             "p95_ms",
             "p99_ms",
             "fetch_to_resident_p95_ms",
             "bytes_read",
             "unique_bytes",
             "budget",
             "peak_resident",
             "peak_rss_anon",
             "peak_rss_file",
             "peak_rss (ru_maxrss)",
             "debt_frames",
             "stalled_frames",
             "max_frames_to_full_quality",
             "failed_pages"});
    replayTable.addRow(
            {std::to_string(summary.value("frames", 0)),
             formatNumber(summary.value("p50_ms", 0.0)),
             formatNumber(summary.value("p95_ms", 0.0)),
             formatNumber(summary.value("p99_ms", 0.0)),
             formatNumber(summary.value("fetch_to_resident_p95_ms", 0.0)),
             bytesCell(summary, "bytes_read"),
             bytesCell(summary, "unique_bytes"),
             bytesCell(summary, "budget_bytes"),
             bytesCell(summary, "peak_resident_bytes"),
             bytesCell(summary, "peak_rss_anon_bytes"),
             bytesCell(summary, "peak_rss_file_bytes"),
             runtime::formatBytes(replay.peakRssBytes),
             std::to_string(summary.value("debt_frames", 0)),
             std::to_string(summary.value("stalled_frames", 0)),
             summary.contains("max_frames_to_full_quality") && summary["max_frames_to_full_quality"].is_number()
                     ? std::to_string(summary["max_frames_to_full_quality"].get<std::int64_t>())
                     : "never (" + std::to_string(summary.value("never_converged", 0)) + " segments)",
             std::to_string(summary.value("failed_pages", 0))});

    std::ostringstream md;
    const std::string buildFlags =
            p.scene.buildFlags.empty() ? "" : " " + joined(p.scene.buildFlags);
    md << "`" << options.command << "`: a child `farfield build" << buildFlags
       << "`, then `farfield " << joined(p.path.commandArgs("SCENE", "PATH.json"))
       << "` and a child `farfield replay --cache-mb " << p.cache.cacheMb
       << " --uploads-per-frame " << p.cache.uploadsPerFrame << "` at " << p.size[0] << "x" << p.size[1]
       << ", asynchronous. Peak RSS is each child's ru_maxrss; the replay also reports its own "
          "peak split into "
       << "anonymous and file-backed pages.\n\n**Build**\n\n"
       << buildTable.markdown() << "\n**Replay** (per frame: `" << name << ".csv`; summary: `"
       << name << "-summary.json`)\n\n"
       << replayTable.markdown() << "\n![replay timeline](" << name << ".png)\n";
    std::filesystem::remove(report);
    std::filesystem::remove(path);
    return scenarioRun.finish("replay", frames, md.str());
}

} // namespace

Result<BenchRun> prepareReplay(const Scenario& scenario) {
    ReplayParams p;
    ScenarioReader reader = readScenario(scenario);
    p.scene = readSceneSpec(reader);
    p.size = reader.size("size", p.size);
    p.path = readPathSpec(reader, p.path, 1);
    p.cache = readCacheSpec(reader, p.cache, 1);
    FF_RETURN_IF_ERROR(reader.finish());
    return BenchRun(
            [p, scenario](const BenchOptions& options) { return runReplay(p, scenario, options); });
}

} // namespace ff::bench
