// "render" scenarios: what one complete frame costs a `farfield render` process. The scene is
// built by a child `farfield build`; each view is rendered by a child `farfield render` (every
// page mapped, the frame complete), so its peak RSS (ru_maxrss) is the frame's own: the scene
// file's mapped pages it touches, the traversal's bounded batches, the renderer's buffers.
// A view may name a limit its peak RSS must stay under (issue 14: the 2 M-atom molecule's
// 1.6 G instanced triangles within 1 GiB). Keys: bench/README.md.

#include "BenchSupport.h"
#include "ScenarioParts.h"

#include <ff/bench/Benchmarks.h>
#include <ff/runtime/Percentile.h>
#include <ff/runtime/Units.h>

#include <nlohmann/json.hpp>

#include <cstdio>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace ff::bench {

namespace {

struct RenderView {
    std::string label;
    std::vector<std::string> flags; ///< appended to `farfield render`
};

struct RenderParams {
    SceneSpec scene;
    std::array<int, 2> size = {640, 480};
    std::vector<RenderView> views = {{"default", {}}};
    std::string rssLimit; ///< a byte size, or empty
};

/** The p50 frame time after the first (cold) frame; the only frame's if there is one. The last
 *  frame alone swings with the machine (and the first few after a cold one run slower). */
double warmMedianMs(const nlohmann::json& frames) {
    std::vector<double> times;
    for (std::size_t i = frames.size() > 1 ? 1 : 0; i < frames.size(); ++i)
        times.push_back(frames[i].value("total_ms", 0.0));
    return runtime::percentile(std::move(times), 0.5);
}

Status runRender(const RenderParams& p, const Scenario& scenario, const BenchOptions& options) {
    ScenarioRun scenarioRun(scenario, options);
    const std::filesystem::path& work = scenarioRun.work();
    const std::filesystem::path scenePath = work / (scenario.name + ".ffs");
    std::fprintf(stderr, "%s: building the scene\n", scenario.name.c_str());
    FF_ASSIGN_OR_RETURN(const ChildRun build, buildScene(p.scene, {}, scenePath, options.selfExe));
    std::uint64_t limit = 0; // checked when the scenario was read
    if (auto parsed = runtime::parseByteSize(p.rssLimit); !p.rssLimit.empty() && parsed)
        limit = *parsed;

    CsvTable table(
            {"view",
             "width",
             "height",
             "seconds",
             "peak_rss_bytes",
             "rss_limit_bytes",
             "within_limit",
             "nodes_visited",
             "triangles_drawn",
             "cubes_drawn",
             "select_ms",
             "draw_ms",
             "file_bytes",
             "build_seconds",
             "build_peak_rss_bytes",
             // Occlusion culling (issue 15): the last frame's, and the first (cold) frame's time.
             "nodes_occluded",
             "occlusion_queries",
             "queries_waited",
             "occlusion_ms",
             "total_ms",
             "frames",
             "first_total_ms",
             "triangles_occluded",
             "warm_median_ms"});
    for (const RenderView& view : p.views) {
        std::fprintf(stderr, "%s: view %s\n", scenario.name.c_str(), view.label.c_str());
        const std::filesystem::path stats = work / (view.label + "-stats.json");
        std::vector<std::string> argv = {
                options.selfExe,
                "render",
                scenePath.string(),
                "--size",
                std::to_string(p.size[0]) + "x" + std::to_string(p.size[1]),
                "--stats",
                stats.string()};
        argv.insert(argv.end(), view.flags.begin(), view.flags.end());
        FF_ASSIGN_OR_RETURN(const ChildRun render, runChild(argv));
        FF_ASSIGN_OR_RETURN(
                const nlohmann::json report, readJsonObject(stats, "render statistics"));
        const nlohmann::json frames = report.value("frames", nlohmann::json::array());
        const nlohmann::json frame = frames.empty() ? nlohmann::json::object() : frames.back();
        const nlohmann::json first = frames.empty() ? nlohmann::json::object() : frames.front();
        table.addRow(
                {view.label,
                 std::to_string(p.size[0]),
                 std::to_string(p.size[1]),
                 formatNumber(render.seconds),
                 std::to_string(render.peakRssBytes),
                 limit ? std::to_string(limit) : "",
                 limit ? (render.peakRssBytes <= limit ? "yes" : "no") : "",
                 std::to_string(frame.value("nodes_visited", std::uint64_t{0})),
                 std::to_string(frame.value("triangles_drawn", std::uint64_t{0})),
                 std::to_string(frame.value("cubes_drawn", std::uint64_t{0})),
                 formatNumber(frame.value("select_ms", 0.0)),
                 formatNumber(frame.value("draw_ms", 0.0)),
                 std::to_string(std::filesystem::file_size(scenePath)),
                 formatNumber(build.seconds),
                 std::to_string(build.peakRssBytes),
                 std::to_string(frame.value("nodes_occluded", std::uint64_t{0})),
                 std::to_string(frame.value("occlusion_queries", std::uint64_t{0})),
                 std::to_string(frame.value("queries_waited", std::uint64_t{0})),
                 formatNumber(frame.value("occlusion_ms", 0.0)),
                 formatNumber(frame.value("total_ms", 0.0)),
                 std::to_string(frames.size()),
                 formatNumber(first.value("total_ms", 0.0)),
                 std::to_string(frame.value("triangles_occluded", std::uint64_t{0})),
                 formatNumber(warmMedianMs(frames))});
        std::filesystem::remove(stats);
    }
    std::filesystem::remove(scenePath);
    const std::filesystem::path csv = scenarioRun.output(".csv");
    FF_RETURN_IF_ERROR(table.write(csv));
    std::ostringstream md;
    md << "`" << options.command << "`: scene "
       << (p.scene.gltf.empty() ? "`--generate " + p.scene.generate + "`"
                                : "`" + p.scene.gltf + "`")
       << ", one child `farfield render` per view (its flags; the last frame's statistics, "
          "first_total_ms the first frame's, warm_median_ms the p50 of the frames after the "
          "first) at "
       << p.size[0] << "x" << p.size[1] << " (every page mapped); peak RSS is the child's ru_maxrss"
       << (limit ? ", against a limit of " + runtime::formatBytes(limit) : std::string()) << ".\n\n"
       << table.markdown() << "\n![peak memory of a frame](" << scenario.name << ".png)\n";
    return scenarioRun.finish("render", csv, md.str());
}

} // namespace

Result<BenchRun> prepareRender(const Scenario& scenario) {
    RenderParams p;
    ScenarioReader reader = readScenario(scenario);
    p.scene = readSceneSpec(reader);
    p.size = reader.size("size", p.size);
    p.rssLimit = reader.string("rss_limit", "");
    if (!p.rssLimit.empty() && !runtime::parseByteSize(p.rssLimit))
        reader.fail("rss_limit", "\"" + p.rssLimit + "\" is not a byte size like 1GiB");
    if (reader.has("views")) {
        p.views.clear();
        for (ScenarioReader& view : reader.objects("views")) {
            RenderView v;
            v.label = view.string("label", "");
            v.flags = view.strings("flags", {});
            if (v.label.empty())
                view.fail("label", "missing: a name for the view");
            p.views.push_back(std::move(v));
        }
        if (p.views.empty())
            reader.fail("views", "needs at least one view");
    }
    FF_RETURN_IF_ERROR(reader.finish());
    return BenchRun(
            [p, scenario](const BenchOptions& options) { return runRender(p, scenario, options); });
}

} // namespace ff::bench
