// Scene file formats side by side: every scene built as format 1 and format 2 by a child
// `farfield build`, one after the other, then `farfield check` on each (checksums, and for
// format 2 every node and cluster decoded): bytes a triangle, build time, peak RSS, check rate.

#include "BenchSupport.h"
#include "ScenarioParts.h"

#include <ff/bench/Benchmarks.h>

#include <nlohmann/json.hpp>

#include <cstdio>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

namespace ff::bench {

namespace {

struct FormatScene {
    std::string label;
    SceneSpec spec;
};

struct FormatParams {
    std::vector<FormatScene> scenes;
    std::vector<std::int64_t> formats = {1, 2};
};

double perTriangle(std::uint64_t bytes, std::uint64_t triangles) {
    return triangles == 0 ? 0.0 : static_cast<double>(bytes) / static_cast<double>(triangles);
}

Status runFormat(const FormatParams& p, const Scenario& scenario, const BenchOptions& options) {
    ScenarioRun scenarioRun(scenario, options);
    const std::filesystem::path& work = scenarioRun.work();
    CsvTable table({"scene", "format", "triangles", "file_bytes", "bytes_per_triangle", "geometry_bytes_per_triangle",
                    "node_bytes_per_triangle", "table_bytes", "nodes", "nodes_per_triangle", "page_size", "clusters",
                    "build_seconds", "peak_rss_bytes", "spill_bytes", "check_seconds", "check_triangles_per_second"});
    for (const FormatScene& scene : p.scenes) {
        for (const std::int64_t format : p.formats) {
            std::fprintf(stderr, "%s: %s as format %lld\n", scenario.name.c_str(), scene.label.c_str(),
                         static_cast<long long>(format));
            const std::filesystem::path file = work / "scene.ffs";
            const std::filesystem::path report = work / "scene.json";
            FF_ASSIGN_OR_RETURN(
                    const ChildRun built,
                    buildScene(scene.spec, {"--format", std::to_string(format), "--report", report.string()}, file,
                               options.selfExe));
            FF_ASSIGN_OR_RETURN(const nlohmann::json json, readJsonObject(report, "build report"));
            FF_ASSIGN_OR_RETURN(const ChildRun checked, runChild({options.selfExe, "check", file.string()}));
            // What survived the NaN and degenerate filters: the denominator.
            const auto triangles = json.value("input_triangles", std::uint64_t{0}) -
                                   json.value("dropped_non_finite_triangles", std::uint64_t{0}) -
                                   json.value("dropped_degenerate_triangles", std::uint64_t{0});
            const nlohmann::json& bytes = json["bytes"];
            const auto fileBytes = bytes.value("file", std::uint64_t{0});
            const auto nodes = json.value("nodes", std::uint64_t{0});
            table.addRow({scene.label, std::to_string(format), std::to_string(triangles), std::to_string(fileBytes),
                          formatNumber(perTriangle(fileBytes, triangles), 2),
                          formatNumber(perTriangle(bytes.value("geometry", std::uint64_t{0}), triangles), 2),
                          formatNumber(perTriangle(bytes.value("nodes", std::uint64_t{0}), triangles), 2),
                          std::to_string(bytes.value("tables", std::uint64_t{0})), std::to_string(nodes),
                          formatNumber(perTriangle(nodes, triangles), 4), std::to_string(json.value("page_size", 0u)),
                          std::to_string(json["clusters"].value("count", std::uint64_t{0})),
                          formatNumber(built.seconds, 3), std::to_string(built.peakRssBytes),
                          std::to_string(bytes.value("spill", std::uint64_t{0})), formatNumber(checked.seconds, 3),
                          formatNumber(static_cast<double>(triangles) / checked.seconds, 0)});
            std::filesystem::remove(file);
            std::filesystem::remove(report);
        }
    }
    const std::filesystem::path csv = options.outDir / (scenario.name + ".csv");
    FF_RETURN_IF_ERROR(table.write(csv));
    std::ostringstream md;
    md << "`" << options.command << "`: each scene built by a child `farfield build --format F` (format 1, then 2), "
       << "then `farfield check` on the file (every page's checksum; format 2 also walks every node and decodes "
       << "every cluster page once). Bytes a triangle: the whole file over the triangles that survive the NaN and "
       << "degenerate filters; peak RSS is the build's ru_maxrss.\n\n"
       << table.markdown() << "\n![bytes a triangle and build time](" << scenario.name << ".png)\n";
    return scenarioRun.finish("format", csv, md.str());
}

} // namespace

Result<BenchRun> prepareFormat(const Scenario& scenario) {
    FormatParams p;
    ScenarioReader reader = readScenario(scenario);
    for (ScenarioReader& s : reader.objects("scenes")) {
        FormatScene scene;
        scene.label = s.string("label", "");
        scene.spec = readSceneSpec(s);
        if (scene.label.empty() || scene.label.find(',') != std::string::npos)
            s.fail("label", "needs a label without commas (it is a CSV cell)");
        p.scenes.push_back(std::move(scene));
    }
    if (p.scenes.empty())
        reader.fail("scenes", "needs at least one scene");
    p.formats = reader.ladder("formats", p.formats);
    for (const std::int64_t f : p.formats)
        if (f != 1 && f != 2)
            reader.fail("formats", "formats are 1 and 2");
    FF_RETURN_IF_ERROR(reader.finish());
    return BenchRun([p, scenario](const BenchOptions& options) { return runFormat(p, scenario, options); });
}

} // namespace ff::bench
