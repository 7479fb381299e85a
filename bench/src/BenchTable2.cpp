// Chamberlain, DeRose, Lischinski, Salesin, Snyder, GI '96, Table 2: the tree seen 30 degrees
// off a sampled axis at 1.75, 3.5, 7 and 14 radii; geometric against hierarchical time, cube
// faces per level, triangles drawn; plus accuracy against a 4x4 supersampled reference.

#include "BenchSupport.h"
#include "ScenarioParts.h"

#include <ff/bench/Benchmarks.h>
#include <ff/runtime/ImageMetrics.h>
#include <ff/runtime/OffscreenContext.h>

#include <array>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

namespace ff::bench {

namespace {

struct Table2Params {
    std::string generate = "forest:trees=1";
    std::vector<std::array<int, 2>> sizes = {{124, 124}, {640, 480}};
    std::vector<double> distances = {1.75, 3.5, 7.0, 14.0};
    float azimuth = 30.0f;
    float elevation = 0.0f;
    float fov = 45.0f;
    float eps = 1.0f;
    int supersample = 4;
    /** Flags the build gets ("build": ["--format", "2"]). */
    std::vector<std::string> buildFlags;
};

Status runTable2(const Table2Params& p, const Scenario& scenario, const BenchOptions& options) {
    ScenarioRun scenarioRun(scenario, options);
    const std::filesystem::path& work = scenarioRun.work();
    const std::filesystem::path scene = work / "tree.ffs";
    std::fprintf(stderr, "%s: building %s\n", scenario.name.c_str(), p.generate.c_str());
    FF_RETURN_IF_ERROR(buildScene({"", p.generate, p.buildFlags}, {}, scene, options.selfExe).status());
    FF_ASSIGN_OR_RETURN(auto context, runtime::OffscreenContext::create());
    FF_ASSIGN_OR_RETURN(auto session, runtime::StreamingSession::open(scene));
    const storage::SceneIndex* file = &session->scene();
    const runtime::Bounds bounds{{file->header().boundsMin[0], file->header().boundsMin[1], file->header().boundsMin[2]},
                                 {file->header().boundsMax[0], file->header().boundsMax[1], file->header().boundsMax[2]}};

    CsvTable table({"width", "height", "distance_radii", "full_ms", "hierarchical_ms", "speedup", "triangles_full",
                    "triangles_hierarchical", "cubes", "cube_faces", "cube_faces_per_level", "psnr_hierarchical_db",
                    "psnr_full_db", "ssim_hierarchical", "ssim_full", "holes_hierarchical", "holes_full"});
    for (const auto& size : p.sizes) {
        for (const double distance : p.distances) {
            const auto d = static_cast<float>(distance);
            std::fprintf(stderr, "%s: %dx%d at %.2f radii\n", scenario.name.c_str(), size[0], size[1], distance);
            const runtime::Camera camera = runtime::Camera::orbit(bounds, d, p.azimuth, p.elevation, glm::radians(p.fov));
            runtime::SelectionOptions full;
            full.method = runtime::Method::Full;
            runtime::SelectionOptions hierarchical;
            hierarchical.epsilonPixels = p.eps;
            FF_ASSIGN_OR_RETURN(
                    const runtime::Frame reference, session->render(frameAt(camera, full, size[0], size[1], p.supersample)));
            FF_ASSIGN_OR_RETURN(const runtime::Frame fullFrame,
                                timeFrames(*session, frameAt(camera, full, size[0], size[1]), 1, options.timedFrames));
            FF_ASSIGN_OR_RETURN(const runtime::Frame hierFrame,
                                timeFrames(*session, frameAt(camera, hierarchical, size[0], size[1]), 1, options.timedFrames));
            FF_ASSIGN_OR_RETURN(const runtime::ColorError hierError, runtime::colorError(hierFrame.image, reference.image));
            FF_ASSIGN_OR_RETURN(const runtime::ColorError fullError, runtime::colorError(fullFrame.image, reference.image));
            FF_ASSIGN_OR_RETURN(const double hierSsim, runtime::ssim(hierFrame.image, reference.image));
            FF_ASSIGN_OR_RETURN(const double fullSsim, runtime::ssim(fullFrame.image, reference.image));
            FF_ASSIGN_OR_RETURN(const runtime::CoverageError holes, runtime::coverageError(hierFrame.image, reference.image));
            FF_ASSIGN_OR_RETURN(const runtime::CoverageError fullHoles, runtime::coverageError(fullFrame.image, reference.image));
            std::string perLevel;
            for (std::size_t l = 0; l < hierFrame.stats.cubeFacesPerLevel.size(); ++l)
                if (hierFrame.stats.cubeFacesPerLevel[l] > 0) {
                    // Appended piece by piece: GCC 12's false -Wrestrict (bug 105329) in Release.
                    if (!perLevel.empty())
                        perLevel += ' ';
                    perLevel += 'L';
                    perLevel += std::to_string(l);
                    perLevel += ':';
                    perLevel += std::to_string(hierFrame.stats.cubeFacesPerLevel[l]);
                }
            table.addRow({std::to_string(size[0]), std::to_string(size[1]), formatNumber(d),
                          formatNumber(fullFrame.stats.totalMs), formatNumber(hierFrame.stats.totalMs),
                          formatNumber(fullFrame.stats.totalMs / hierFrame.stats.totalMs),
                          std::to_string(fullFrame.stats.trianglesDrawn), std::to_string(hierFrame.stats.trianglesDrawn),
                          std::to_string(hierFrame.stats.cubesDrawn), std::to_string(hierFrame.stats.cubeFacesDrawn),
                          perLevel.empty() ? "-" : perLevel, formatNumber(hierError.psnrSrgb), formatNumber(fullError.psnrSrgb),
                          formatNumber(hierSsim, 4), formatNumber(fullSsim, 4), std::to_string(holes.holes),
                          std::to_string(fullHoles.holes)});
        }
    }
    const std::filesystem::path csv = options.outDir / (scenario.name + ".csv");
    FF_RETURN_IF_ERROR(table.write(csv));
    std::ostringstream md;
    md << "`" << options.command << "` on " << file->header().storedTriangles << " triangles (the paper's tree: 52,470), "
       << "viewed " << p.azimuth << " degrees about the vertical axis from a sampled direction, at d scene radii, "
       << "epsilon = " << p.eps << " pixel. "
       << "Times are the median of " << options.timedFrames << " frames (selection + drawing until glFinish) on "
       << "llvmpipe; PSNR/SSIM against the same view with all geometry, " << p.supersample << "x" << p.supersample
       << " supersampled." << buildFlagsNote(p.buildFlags) << "\n\n"
       << table.markdown() << "\n![speed against accuracy](" << scenario.name << ".png)\n";
    return scenarioRun.finish("table2", csv, md.str());
}

} // namespace

Result<BenchRun> prepareTable2(const Scenario& scenario) {
    Table2Params p;
    ScenarioReader reader = readScenario(scenario);
    p.generate = reader.string("generate", p.generate);
    p.sizes = reader.sizes("sizes", p.sizes);
    p.distances = reader.numbers("distances", p.distances);
    p.azimuth = static_cast<float>(reader.number("azimuth", p.azimuth));
    p.elevation = static_cast<float>(reader.number("elevation", p.elevation));
    p.fov = static_cast<float>(reader.number("fov", p.fov));
    p.eps = static_cast<float>(reader.number("eps", p.eps));
    p.supersample = readReferenceSupersample(reader, p.supersample);
    p.buildFlags = readBuildFlags(reader);
    for (const double d : p.distances)
        if (!(d > 0.0))
            reader.fail("distances", "must be positive (scene radii)");
    if (!(p.fov > 0.0f && p.fov < 179.0f))
        reader.fail("fov", "must be between 0 and 179 degrees");
    if (!(p.eps >= 0.0f))
        reader.fail("eps", "must be >= 0 pixels");
    FF_RETURN_IF_ERROR(reader.finish());
    return BenchRun([p, scenario](const BenchOptions& options) { return runTable2(p, scenario, options); });
}

} // namespace ff::bench
