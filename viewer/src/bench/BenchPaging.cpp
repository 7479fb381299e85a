// Paging behaviour (issue "out-of-core streaming"): how many bytes a complete frame needs as the
// scene grows (the working set Chamberlain et al. argue grows like log n), and how a cold cache
// recovers from teleports across a flat terrain. Every step runs child `farfield` processes, so
// each replay's memory is its own.

#include "BenchSupport.h"
#include "Benchmarks.h"

#include <nlohmann/json.hpp>

#include <cstdio>
#include <fstream>

namespace ff::viewer::bench {

namespace {

nlohmann::json readJson(const std::filesystem::path& path) {
    std::ifstream in(path);
    return nlohmann::json::parse(in, nullptr, false);
}

} // namespace

Status runPaging(const BenchOptions& options) {
    std::filesystem::create_directories(options.outDir);
    const std::filesystem::path work = options.workDir.empty() ? options.outDir / "scenes" : options.workDir;
    std::filesystem::create_directories(work);
    const std::string& ff = options.selfExe;
    const std::filesystem::path scene = work / "paging.ffs";
    const std::filesystem::path path = work / "path.json";
    const std::filesystem::path summary = work / "summary.json";

    // ---- working set of a complete frame against scene size --------------------------------
    struct Step {
        std::string family;
        std::string spec;
    };
    std::vector<Step> ladder;
    for (int trees = 1; trees <= (options.quick ? 64 : 16384); trees *= 4)
        ladder.push_back({"forest", "forest:trees=" + std::to_string(trees)});
    for (long long triangles : options.quick ? std::vector<long long>{1'000'000} : std::vector<long long>{1'000'000, 4'000'000, 16'000'000, 64'000'000})
        ladder.push_back({"terrain", "terrain:triangles=" + std::to_string(triangles)});
    CsvTable workingSet({"family", "spec", "triangles", "file_bytes", "complete_frame_bytes", "node_page_bytes",
                         "geometry_page_bytes", "nodes_visited", "triangles_drawn", "frame_ms"});
    for (const Step& step : ladder) {
        std::fprintf(stderr, "paging: working set of %s\n", step.spec.c_str());
        FF_RETURN_IF_ERROR(runChild({ff, "build", "-q", "--generate", step.spec, "-o", scene.string(), "--report",
                                     (work / "report.json").string()})
                                   .status());
        // One view, the same in scene radii for every size: the orbit's first frame.
        FF_RETURN_IF_ERROR(runChild({ff, "path", "orbit", scene.string(), "-o", path.string(), "--frames", "1"}).status());
        FF_RETURN_IF_ERROR(runChild({ff, "replay", scene.string(), path.string(), "--sync", "--cache-mb", "4096",
                                     "--summary", summary.string()})
                                   .status());
        const nlohmann::json report = readJson(work / "report.json");
        const nlohmann::json s = readJson(summary);
        if (!report.is_object() || !s.is_object())
            return Status(ErrorCode::Internal, "unreadable child report for " + step.spec);
        workingSet.addRow({step.family, step.spec, std::to_string(report.value("instanced_triangles", std::uint64_t{0})),
                           std::to_string(report["bytes"].value("file", std::uint64_t{0})),
                           std::to_string(s.value("peak_resident_bytes", std::uint64_t{0})),
                           std::to_string(s.value("frame_node_bytes", std::uint64_t{0})),
                           std::to_string(s.value("frame_geometry_bytes", std::uint64_t{0})),
                           std::to_string(s.value("frame_nodes_visited", std::uint64_t{0})),
                           std::to_string(s.value("frame_triangles_drawn", std::uint64_t{0})),
                           formatNumber(s.value("p50_ms", 0.0))});
    }
    FF_RETURN_IF_ERROR(workingSet.write(options.outDir / "paging-working-set.csv"));

    // ---- teleports across a terrain, cold cache ---------------------------------------------
    const std::string terrain = options.quick ? "terrain:triangles=1000000" : "terrain:triangles=16000000";
    const std::string teleports = options.quick ? "5" : "20";
    std::fprintf(stderr, "paging: %s teleports across %s\n", teleports.c_str(), terrain.c_str());
    FF_RETURN_IF_ERROR(runChild({ff, "build", "-q", "--generate", terrain, "-o", scene.string()}).status());
    FF_RETURN_IF_ERROR(runChild({ff, "path", "teleports", scene.string(), "-o", path.string(), "--frames",
                                 options.quick ? "100" : "400", "--teleports", teleports, "--seed", "3"})
                               .status());
    const std::filesystem::path frames = options.outDir / "paging-teleports.csv";
    FF_RETURN_IF_ERROR(runChild({ff, "replay", scene.string(), path.string(), "--cache-mb", "64", "--csv",
                                 frames.string(), "--summary", (options.outDir / "paging-teleports-summary.json").string()})
                               .status());
    FF_RETURN_IF_ERROR(plotCharts("paging", options.outDir / "paging-working-set.csv", options.outDir));

    const nlohmann::json t = readJson(options.outDir / "paging-teleports-summary.json");
    std::ofstream md(options.outDir / "paging.md");
    md << "# Paging behaviour\n\n"
       << "`farfield bench paging`. **Working set**: the bytes resident for one complete frame (`replay --sync`, "
       << "epsilon = 1, 640x480, the first frame of `farfield path orbit`: the same view in scene radii for every "
       << "size) against scene size.\n\n"
       << workingSet.markdown() << "\n![working set against scene size](paging-working-set.png)\n\n"
       << "**Teleports**: " << teleports << " jumps across `" << terrain << "` with a cold 64 MiB cache, "
       << "asynchronous (`paging-teleports.csv` per frame, summary below).\n\n```json\n"
       << t.dump(2) << "\n```\n\n![teleport timeline](paging-teleports.png)\n";
    if (options.workDir.empty())
        std::filesystem::remove_all(work);
    return Status::ok();
}

} // namespace ff::viewer::bench
