// Builder throughput and peak memory on flat terrain ladders. Each build runs as a child
// `farfield build` so its peak RSS (ru_maxrss) is its own.

#include "BenchSupport.h"
#include "Benchmarks.h"

#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <sys/resource.h>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>

namespace ff::viewer::bench {

Status runBuild(const BenchOptions& options) {
    std::filesystem::create_directories(options.outDir);
    const std::filesystem::path work = options.workDir.empty() ? options.outDir / "scenes" : options.workDir;
    std::filesystem::create_directories(work);
    const unsigned cores = std::max(1u, std::thread::hardware_concurrency());

    struct Step {
        std::uint64_t triangles;
        std::string budget;
    };
    std::vector<Step> ladder;
    if (options.quick)
        ladder = {{1'000'000, "256MiB"}, {4'000'000, "256MiB"}};
    else
        ladder = {{1'000'000, "1GiB"}, {4'000'000, "1GiB"}, {16'000'000, "1GiB"}, {64'000'000, "1GiB"},
                  {200'000'000, "1GiB"}, {16'000'000, "64MiB"}, {64'000'000, "256MiB"}};

    CsvTable table({"triangles", "budget", "budget_bytes", "seconds", "triangles_per_second",
                    "triangles_per_second_per_core", "peak_rss_bytes", "rss_minus_budget_bytes", "file_bytes", "chunks",
                    "spill_bytes"});
    for (const Step& step : ladder) {
        std::fprintf(stderr, "build: terrain of %llu triangles, budget %s\n",
                     static_cast<unsigned long long>(step.triangles), step.budget.c_str());
        const std::filesystem::path scene = work / "terrain.ffs";
        const std::filesystem::path report = work / "terrain.json";
        FF_ASSIGN_OR_RETURN(const ChildRun run,
                            runChild({options.selfExe, "build", "--generate", "terrain:triangles=" + std::to_string(step.triangles),
                                      "-o", scene.string(), "--memory-budget", step.budget, "--report", report.string(), "-q"}));
        std::ifstream in(report);
        const nlohmann::json json = nlohmann::json::parse(in, nullptr, false);
        if (!json.is_object())
            return Status(ErrorCode::Internal, "unreadable build report " + report.string());
        const auto triangles = json.value("input_triangles", std::uint64_t{0});
        const auto budgetBytes = json.value("memory_budget_bytes", std::uint64_t{0});
        const double rate = static_cast<double>(triangles) / run.seconds;
        table.addRow({std::to_string(triangles), step.budget, std::to_string(budgetBytes), formatNumber(run.seconds),
                      formatNumber(rate, 0), formatNumber(rate / cores, 0), std::to_string(run.peakRssBytes),
                      std::to_string(static_cast<std::int64_t>(run.peakRssBytes) - static_cast<std::int64_t>(budgetBytes)),
                      std::to_string(json["bytes"].value("file", std::uint64_t{0})),
                      std::to_string(json.value("chunks", std::uint64_t{0})),
                      std::to_string(json["bytes"].value("spill", std::uint64_t{0}))});
        std::filesystem::remove(scene);
        std::filesystem::remove(report);
    }
    const std::filesystem::path csv = options.outDir / "build.csv";
    FF_RETURN_IF_ERROR(table.write(csv));
    FF_RETURN_IF_ERROR(plotCharts("build", csv, options.outDir));
    std::ofstream md(options.outDir / "build.md");
    md << "# Builder throughput and memory\n\n"
       << "`farfield bench build`: `farfield build --generate terrain:triangles=N` end to end (generate, spill, "
       << "partition, octree, cubes, write, fsync) on " << cores << " cores; peak RSS is the child's ru_maxrss.\n\n"
       << table.markdown() << "\n![throughput and memory](build.png)\n";
    if (options.workDir.empty())
        std::filesystem::remove_all(work);
    return Status::ok();
}

} // namespace ff::viewer::bench
