// Chamberlain et al. '96 §5.2: a forest made by recursively instancing the tree, 1 to 16,384
// trees, rendered from one fixed viewpoint; frame time against scene size on log-log axes.

#include "BenchSupport.h"
#include "ScenarioParts.h"

#include <ff/bench/Benchmarks.h>
#include <ff/runtime/OffscreenContext.h>

#include <array>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

namespace ff::bench {

namespace {

struct ForestParams {
    std::vector<std::int64_t> trees = {1, 4, 16, 64, 256, 1024, 4096, 16384};
    /** The paper's image size (Table 2) and a common window size. */
    std::vector<std::array<int, 2>> sizes = {{124, 124}, {640, 480}};
    float eps = 1.0f;
    /** Above this many triangles the full (brute-force) frame is not rendered but extrapolated
     *  from the per-triangle cost measured at the largest rendered size (llvmpipe: ~2.5 M
     *  triangles/s). */
    std::int64_t fullMeasuredLimit = 60'000'000;
    /** Also draw each forest with occlusion culling (the default backend): its frame time and
     *  speedup in columns of their own. */
    bool occlusion = false;
    /** Flags every build gets ("build": ["--format", "2"]). */
    std::vector<std::string> buildFlags;
};

Status runForest(const ForestParams& p, const Scenario& scenario, const BenchOptions& options) {
    ScenarioRun scenarioRun(scenario, options);
    const std::filesystem::path& work = scenarioRun.work();
    FF_ASSIGN_OR_RETURN(auto context, runtime::OffscreenContext::create());

    // One viewpoint for every forest, relative to the corner where the forest starts: outside
    // the corner tree, looking diagonally into the forest and over it to the horizon. The near
    // field is the same for every size; larger forests add trees ever further away (the
    // setting of the paper's Plate 5 and Fig. 5).
    auto cornerCamera = [](const storage::SceneIndex& file) {
        const glm::vec3 corner(file.header().boundsMin[0], 0.0f, file.header().boundsMin[2]);
        runtime::Camera c = runtime::Camera::lookAt(corner + glm::vec3(-12.0f, 18.0f, -12.0f),
                                                    corner + glm::vec3(30.0f, 2.0f, 30.0f), {0, 1, 0}, glm::radians(60.0f));
        c.zNear = 0.5f;
        c.zFar = 20000.0f;
        return c;
    };

    CsvTable table({"width", "height", "trees", "triangles", "full_ms", "full_measured", "hierarchical_ms", "speedup", "triangles_drawn",
                    "cubes_drawn", "nodes_visited", "file_bytes", "occlusion_ms", "occlusion_speedup",
                    "occlusion_triangles_drawn", "occlusion_queries", "nodes_occluded"});
    std::vector<double> fullMsPerTriangle(p.sizes.size(), 0.0);
    const auto fullMeasuredLimit = static_cast<std::uint64_t>(p.fullMeasuredLimit);
    for (const std::int64_t trees : p.trees) {
        std::fprintf(stderr, "%s: %lld trees\n", scenario.name.c_str(), static_cast<long long>(trees));
        const std::filesystem::path scene = work / ("forest-" + std::to_string(trees) + ".ffs");
        FF_RETURN_IF_ERROR(
                buildScene({"", "forest:trees=" + std::to_string(trees), p.buildFlags}, {}, scene, options.selfExe)
                        .status());
        FF_ASSIGN_OR_RETURN(auto session, runtime::StreamingSession::open(scene));
        const storage::SceneIndex* file = &session->scene();
        const std::uint64_t triangles = file->header().instancedTriangles;
        const runtime::Camera camera = cornerCamera(*file);

        for (std::size_t si = 0; si < p.sizes.size(); ++si) {
            const int width = p.sizes[si][0];
            const int height = p.sizes[si][1];
            runtime::SelectionOptions hierarchical;
            hierarchical.epsilonPixels = p.eps;
            FF_ASSIGN_OR_RETURN(const runtime::Frame hier,
                                timeFrames(*session, frameAt(camera, hierarchical, width, height), 1, options.timedFrames));
            double fullMs = 0.0;
            const bool measured = triangles <= fullMeasuredLimit;
            if (measured) {
                runtime::SelectionOptions full;
                full.method = runtime::Method::Full;
                FF_ASSIGN_OR_RETURN(const runtime::Frame frame, timeFrames(*session, frameAt(camera, full, width, height), 1, 1));
                fullMs = frame.stats.totalMs;
                fullMsPerTriangle[si] = fullMs / static_cast<double>(triangles);
            } else {
                fullMs = fullMsPerTriangle[si] * static_cast<double>(triangles);
            }
            std::vector<std::string> occlusionCells(5);
            if (p.occlusion) {
                runtime::FrameContext culled = frameAt(camera, hierarchical, width, height);
                culled.occlusion.enabled = true;
                FF_ASSIGN_OR_RETURN(const runtime::Frame occ, timeFrames(*session, culled, 1, options.timedFrames));
                occlusionCells = {formatNumber(occ.stats.totalMs), formatNumber(fullMs / occ.stats.totalMs, 1),
                                  std::to_string(occ.stats.trianglesDrawn), std::to_string(occ.stats.occlusionQueries),
                                  std::to_string(occ.stats.nodesOccluded)};
            }
            std::vector<std::string> row = {std::to_string(width), std::to_string(height), std::to_string(trees), std::to_string(triangles),
                          formatNumber(fullMs), measured ? "1" : "0", formatNumber(hier.stats.totalMs),
                          formatNumber(fullMs / hier.stats.totalMs, 1), std::to_string(hier.stats.trianglesDrawn),
                          std::to_string(hier.stats.cubesDrawn), std::to_string(hier.stats.nodesVisited),
                          std::to_string(file->pageCount() * file->pageSize())};
            row.insert(row.end(), occlusionCells.begin(), occlusionCells.end());
            table.addRow(std::move(row));
        }
        session.reset();
        std::filesystem::remove(scene);
    }
    const std::filesystem::path csv = options.outDir / (scenario.name + ".csv");
    FF_RETURN_IF_ERROR(table.write(csv));
    std::string sizes;
    for (const auto& size : p.sizes)
        sizes += (sizes.empty() ? "" : " and ") + std::to_string(size[0]) + "x" + std::to_string(size[1]);
    std::ostringstream md;
    md << "`" << options.command << "`: forests of " << p.trees.front() << " to " << p.trees.back()
       << " trees (one ~52.6k-triangle prototype plus one "
       << "transform per tree), one viewpoint fixed at the forest's corner looking diagonally into it and over it to the horizon, at "
       << sizes << " (124x124 is the paper's image size), epsilon = " << p.eps << ". "
       << "Full (brute force) frames are measured up to " << p.fullMeasuredLimit / 1'000'000
       << " M triangles and extrapolated above that from the measured per-triangle cost (full_measured = 0). "
       << "Chamberlain et al. report an 88x speedup at 16,384 trees (859 M polygons)."
       << buildFlagsNote(p.buildFlags)
       << (p.occlusion ? " occlusion_*: the same frames with occlusion culling on (docs/methods.md §9), "
                         "timed like the hierarchical ones; the speedup is over the same full frame."
                       : "")
       << "\n\n"
       << table.markdown() << "\n![frame time against scene size](" << scenario.name << ".png)\n";
    return scenarioRun.finish("forest", csv, md.str());
}

} // namespace

Result<BenchRun> prepareForest(const Scenario& scenario) {
    ForestParams p;
    ScenarioReader reader = readScenario(scenario);
    p.sizes = reader.sizes("sizes", p.sizes);
    p.eps = static_cast<float>(reader.number("eps", p.eps));
    p.fullMeasuredLimit = reader.integer("full_measured_limit", p.fullMeasuredLimit);
    p.trees = reader.ladder("trees", p.trees);
    p.occlusion = reader.boolean("occlusion", p.occlusion);
    p.buildFlags = readBuildFlags(reader);
    if (!(p.eps >= 0.0f))
        reader.fail("eps", "must be >= 0 pixels");
    if (p.fullMeasuredLimit < 0)
        reader.fail("full_measured_limit", "must be >= 0 triangles");
    FF_RETURN_IF_ERROR(reader.finish());
    return BenchRun([p, scenario](const BenchOptions& options) { return runForest(p, scenario, options); });
}

} // namespace ff::bench
