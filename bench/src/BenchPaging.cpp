// Paging behaviour (issue "out-of-core streaming"): how many bytes a complete frame needs as the
// scene grows (the working set Chamberlain et al. argue grows like log n), and how a cold cache
// recovers from teleports across a flat terrain. Every step runs child `farfield` processes, so
// each replay's memory is its own.

#include "BenchSupport.h"
#include "ScenarioParts.h"

#include <ff/bench/Benchmarks.h>

#include <nlohmann/json.hpp>

#include <cstdio>
#include <initializer_list>

namespace ff::bench {

namespace {

struct PagingParams {
    // Working set: forests and terrains of these sizes, one complete (--sync) frame each.
    std::vector<std::int64_t> forestTrees = {1, 4, 16, 64, 256, 1024, 4096, 16384, 65536};
    std::vector<std::int64_t> terrainTriangles = {1'000'000, 4'000'000, 16'000'000, 64'000'000, 256'000'000};
    std::int64_t workingSetCacheMb = 4096;
    // Terrains built with a small --memory-budget: many more chunks for their size, as many as
    // a larger scene would have with the default budget (each chunk is a subtree of its own).
    std::vector<std::int64_t> smallBudgetTriangles;
    std::string smallBudget = "192MiB";
    // Teleports: a cold cache, asynchronous.
    std::int64_t teleportTriangles = 16'000'000;
    std::int64_t teleportFrames = 400;
    std::int64_t teleports = 20;
    std::int64_t teleportSeed = 3;
    std::int64_t teleportCacheMb = 64;
    /** Flags every build gets ("build": ["--format", "2"]). */
    std::vector<std::string> buildFlags;
};

/** `farfield build -q --generate SPEC` with the scenario's flags, then `extra`. */
std::vector<std::string> buildArgs(const PagingParams& p, const std::string& ff, const std::string& spec,
                                   std::initializer_list<std::string> extra) {
    std::vector<std::string> argv = {ff, "build", "-q", "--generate", spec};
    argv.insert(argv.end(), p.buildFlags.begin(), p.buildFlags.end());
    argv.insert(argv.end(), extra);
    return argv;
}

Status runPaging(const PagingParams& p, const Scenario& scenario, const BenchOptions& options) {
    ScenarioRun scenarioRun(scenario, options);
    const std::filesystem::path& work = scenarioRun.work();
    const std::string prefix = scenario.name;
    const std::string& ff = options.selfExe;
    const std::filesystem::path scene = work / "paging.ffs";
    const std::filesystem::path path = work / "path.json";
    const std::filesystem::path summary = work / "summary.json";

    // ---- working set of a complete frame against scene size --------------------------------
    struct Step {
        std::string family;
        std::string spec;
        std::string memoryBudget = "1GiB"; // the build's default
    };
    std::vector<Step> ladder;
    for (const std::int64_t trees : p.forestTrees)
        ladder.push_back({"forest", "forest:trees=" + std::to_string(trees)});
    for (const std::int64_t triangles : p.terrainTriangles)
        ladder.push_back({"terrain", "terrain:triangles=" + std::to_string(triangles)});
    for (const std::int64_t triangles : p.smallBudgetTriangles)
        ladder.push_back({"terrain, built in " + p.smallBudget, "terrain:triangles=" + std::to_string(triangles), p.smallBudget});
    CsvTable workingSet({"family", "spec", "triangles", "file_bytes", "chunks", "complete_frame_bytes", "node_page_bytes",
                         "geometry_page_bytes", "nodes_visited", "triangles_drawn", "frame_ms"});
    for (const Step& step : ladder) {
        std::fprintf(stderr, "%s: working set of %s\n", prefix.c_str(), step.spec.c_str());
        FF_RETURN_IF_ERROR(runChild(buildArgs(p, ff, step.spec,
                                              {"--memory-budget", step.memoryBudget, "-o", scene.string(), "--report",
                                               (work / "report.json").string()}))
                                   .status());
        // One view, the same in scene radii for every size: the orbit's first frame.
        PathSpec orbit{.generator = "orbit", .options = {}};
        orbit.options.frames = 1;
        std::vector<std::string> orbitArgs = orbit.commandArgs(scene, path);
        orbitArgs.insert(orbitArgs.begin(), ff);
        FF_RETURN_IF_ERROR(runChild(orbitArgs).status());
        FF_RETURN_IF_ERROR(runChild({ff, "replay", scene.string(), path.string(), "--sync", "--cache-mb", std::to_string(p.workingSetCacheMb),
                                     "--summary", summary.string()})
                                   .status());
        FF_ASSIGN_OR_RETURN(const nlohmann::json report, readJsonObject(work / "report.json", "build report"));
        FF_ASSIGN_OR_RETURN(const nlohmann::json s, readJsonObject(summary, "replay summary"));
        workingSet.addRow({step.family, step.spec, std::to_string(report.value("instanced_triangles", std::uint64_t{0})),
                           std::to_string(report["bytes"].value("file", std::uint64_t{0})),
                           std::to_string(report.value("chunks", std::uint64_t{0})),
                           std::to_string(s.value("peak_resident_bytes", std::uint64_t{0})),
                           std::to_string(s.value("frame_node_bytes", std::uint64_t{0})),
                           std::to_string(s.value("frame_geometry_bytes", std::uint64_t{0})),
                           std::to_string(s.value("frame_nodes_visited", std::uint64_t{0})),
                           std::to_string(s.value("frame_triangles_drawn", std::uint64_t{0})),
                           formatNumber(s.value("p50_ms", 0.0))});
    }
    const std::filesystem::path workingSetCsv = options.outDir / (prefix + "-working-set.csv");
    FF_RETURN_IF_ERROR(workingSet.write(workingSetCsv));

    // ---- teleports across a terrain, cold cache ---------------------------------------------
    const std::string terrain = "terrain:triangles=" + std::to_string(p.teleportTriangles);
    const std::string teleports = std::to_string(p.teleports);
    std::fprintf(stderr, "%s: %s teleports across %s\n", prefix.c_str(), teleports.c_str(), terrain.c_str());
    FF_RETURN_IF_ERROR(runChild(buildArgs(p, ff, terrain, {"-o", scene.string()})).status());
    PathSpec jumps{.generator = "teleports", .options = {}};
    jumps.options.frames = p.teleportFrames;
    jumps.options.teleports = p.teleports;
    jumps.options.seed = static_cast<std::uint64_t>(p.teleportSeed);
    std::vector<std::string> jumpArgs = jumps.commandArgs(scene, path);
    jumpArgs.insert(jumpArgs.begin(), ff);
    FF_RETURN_IF_ERROR(runChild(jumpArgs).status());
    const std::filesystem::path frames = options.outDir / (prefix + "-teleports.csv");
    const std::filesystem::path teleportSummary = options.outDir / (prefix + "-teleports-summary.json");
    FF_RETURN_IF_ERROR(runChild({ff, "replay", scene.string(), path.string(), "--cache-mb",
                                 std::to_string(p.teleportCacheMb), "--csv", frames.string(), "--summary",
                                 teleportSummary.string()})
                               .status());

    FF_ASSIGN_OR_RETURN(const nlohmann::json t, readJsonObject(teleportSummary, "replay summary"));
    std::ostringstream md;
    md << "`" << options.command << "`. **Working set**: the bytes resident for one complete frame (`replay --sync`, "
       << "epsilon = 1, 640x480, the first frame of `farfield path orbit`: the same view in scene radii for every "
       << "size) against scene size." << buildFlagsNote(p.buildFlags) << "\n\n"
       << workingSet.markdown() << "\n![working set against scene size](" << prefix << "-working-set.png)\n\n"
       << "**Teleports**: " << teleports << " jumps across `" << terrain << "` with a cold " << p.teleportCacheMb
       << " MiB cache, asynchronous (`" << prefix << "-teleports.csv` per frame, summary below).\n\n```json\n"
       << t.dump(2) << "\n```\n\n![teleport timeline](" << prefix << "-teleports.png)\n";
    return scenarioRun.finish("paging", workingSetCsv, md.str());
}

} // namespace

Result<BenchRun> preparePaging(const Scenario& scenario) {
    PagingParams p;
    ScenarioReader reader = readScenario(scenario);
    ScenarioReader ws = reader.object("working_set");
    p.forestTrees = ws.ladder("forest_trees", p.forestTrees);
    p.terrainTriangles = ws.ladder("terrain_triangles", p.terrainTriangles);
    p.workingSetCacheMb = ws.integer("cache_mb", p.workingSetCacheMb);
    ScenarioReader small = ws.object("small_budget");
    if (small.has("terrain_triangles"))
        p.smallBudgetTriangles = small.ladder("terrain_triangles", {});
    p.smallBudget = small.string("memory_budget", p.smallBudget);
    ScenarioReader tp = reader.object("teleports");
    p.teleportTriangles = tp.integer("terrain_triangles", p.teleportTriangles);
    p.teleportFrames = tp.integer("frames", p.teleportFrames);
    p.teleports = tp.integer("jumps", p.teleports);
    p.teleportSeed = tp.integer("seed", p.teleportSeed);
    p.teleportCacheMb = tp.integer("cache_mb", p.teleportCacheMb);
    p.buildFlags = readBuildFlags(reader);
    if (p.workingSetCacheMb < 1)
        ws.fail("cache_mb", "must be >= 1");
    if (p.teleportTriangles < 1 || p.teleportCacheMb < 1 || p.teleportSeed < 0)
        tp.fail("", "terrain_triangles and cache_mb must be >= 1, seed >= 0");
    if (p.teleports < 1 || p.teleportFrames < 2 * p.teleports)
        tp.fail("", "needs jumps >= 1 and frames >= 2 * jumps");
    FF_RETURN_IF_ERROR(reader.finish());
    return BenchRun([p, scenario](const BenchOptions& options) { return runPaging(p, scenario, options); });
}

} // namespace ff::bench
