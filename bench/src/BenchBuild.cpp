// Builder throughput and peak memory on flat terrain ladders. Each build runs as a child
// `farfield build` so its peak RSS (ru_maxrss) is its own.

#include "BenchSupport.h"

#include <ff/bench/Benchmarks.h>
#include <ff/runtime/Units.h>

#include <nlohmann/json.hpp>
#include <sys/resource.h>
#include <sys/wait.h>

#include <chrono>
#include <cstdio>
#include <thread>
#include <unistd.h>

namespace ff::bench {

namespace {

struct Step {
    std::int64_t triangles;
    std::string budget; ///< `farfield build --memory-budget`
};

struct BuildParams {
    std::vector<Step> ladder = {{1'000'000, "1GiB"},  {4'000'000, "1GiB"},   {16'000'000, "1GiB"},
                                {64'000'000, "1GiB"}, {200'000'000, "1GiB"}, {16'000'000, "64MiB"},
                                {64'000'000, "256MiB"}};
};

Status runBuild(const BuildParams& p, const Scenario& scenario, const BenchOptions& options) {
    ScenarioRun scenarioRun(scenario, options);
    const std::filesystem::path& work = scenarioRun.work();
    const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
    const std::vector<Step>& ladder = p.ladder;

    CsvTable table({"triangles", "budget", "budget_bytes", "seconds", "triangles_per_second",
                    "triangles_per_second_per_core", "peak_rss_bytes", "rss_minus_budget_bytes", "file_bytes", "chunks",
                    "spill_bytes"});
    for (const Step& step : ladder) {
        std::fprintf(stderr, "%s: terrain of %lld triangles, budget %s\n", scenario.name.c_str(),
                     static_cast<long long>(step.triangles), step.budget.c_str());
        const std::filesystem::path scene = work / "terrain.ffs";
        const std::filesystem::path report = work / "terrain.json";
        FF_ASSIGN_OR_RETURN(const ChildRun run,
                            // Format 1: what the committed build results measured.
                            runChild({options.selfExe, "build", "--format", "1", "--generate",
                                      "terrain:triangles=" + std::to_string(step.triangles), "-o", scene.string(),
                                      "--memory-budget", step.budget, "--report", report.string(), "-q"}));
        FF_ASSIGN_OR_RETURN(const nlohmann::json json, readJsonObject(report, "build report"));
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
    const std::filesystem::path csv = options.outDir / (scenario.name + ".csv");
    FF_RETURN_IF_ERROR(table.write(csv));
    std::ostringstream md;
    md << "`" << options.command << "`: `farfield build --generate terrain:triangles=N` end to end (generate, spill, "
       << "partition, octree, cubes, write, fsync) on " << cores << " cores; peak RSS is the child's ru_maxrss.\n\n"
       << table.markdown() << "\n![throughput and memory](" << scenario.name << ".png)\n";
    return scenarioRun.finish("build", csv, md.str());
}

} // namespace

Result<BenchRun> prepareBuild(const Scenario& scenario) {
    BuildParams p;
    ScenarioReader reader = readScenario(scenario);
    if (reader.has("ladder")) {
        p.ladder.clear();
        for (ScenarioReader& step : reader.objects("ladder")) {
            const std::int64_t triangles = step.integer("triangles", 0);
            const std::string budget = step.string("budget", "1GiB");
            if (triangles < 1)
                step.fail("triangles", "must be a whole number >= 1");
            if (!runtime::parseByteSize(budget))
                step.fail("budget", "\"" + budget + "\" is not a byte size like 256MiB or 1GiB");
            p.ladder.push_back({triangles, budget});
        }
        if (p.ladder.empty())
            reader.fail("ladder", "needs at least one step");
    }
    FF_RETURN_IF_ERROR(reader.finish());
    return BenchRun([p, scenario](const BenchOptions& options) { return runBuild(p, scenario, options); });
}

} // namespace ff::bench
