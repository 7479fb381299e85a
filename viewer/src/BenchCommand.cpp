// `farfield bench SCENARIO...`: runs scenario files (bench/*.json, format in bench/README.md).
// Every scenario named is read and checked before the first one runs, so a typo in the last
// file costs nothing.

#include "Commands.h"
#include "OutputFile.h"

#include <ff/bench/Benchmarks.h>

#include <unistd.h>
#include <climits>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

namespace ff::viewer {

namespace {

struct BenchArgs {
    std::vector<std::string> scenarios;
    bool list = false;
    bool check = false;
    std::string out = "docs/results";
    std::string work;
    int frames = 3;
    bool quick = false;
    CLI::Option* framesOption = nullptr;
};

constexpr const char* kHelpFooter = R"(
A scenario is a JSON file naming a benchmark kind and its parameters; give its path, or a bare
NAME for bench/NAME.json under the current directory. Each scenario writes OUT/NAME.csv,
OUT/NAME*.png (charts) and OUT/NAME.md (the report, embedding its charts).

Kinds (key "kind"):
  table2   Chamberlain et al. Table 2: the tree at several distances, full against hierarchical
  forest   the recursively instanced forest, frame time against scene size
  build    builder throughput and peak memory on a terrain ladder
  paging   working set against scene size; cold-cache teleports
  views    speed against accuracy: methods at fixed views against a supersampled full
           reference (PSNR, SSIM, holes, over-coverage), optionally swept over a parameter
  path     popping and flicker: methods along a generated camera path, per-frame PSNR and
           temporal instability against per-frame full references; optionally streaming
  replay   a scene built under --memory-budget (time, peak RSS), then a camera path replayed
           through a cold cache of cache_mb: per-frame telemetry, percentiles, bytes read,
           peak RSS anon/file (the scene file is removed afterwards)
--quick applies the scenario's "quick" overrides (smaller ladders: a smoke run, not results).
--frames is the timed frames per measurement of table2, forest and views (the median, after one
warm-up); a path scenario draws each frame of its path once.
Keys and examples: bench/README.md.

Examples:
  farfield bench --list
  farfield bench --check bench/*.json
  farfield bench table2 --out /tmp/results --quick
  farfield bench bench/*.json --out docs/results)";

std::string selfExecutable() {
    char path[PATH_MAX];
    const ssize_t n = readlink("/proc/self/exe", path, sizeof(path) - 1);
    return n > 0 ? std::string(path, static_cast<std::size_t>(n)) : std::string("farfield");
}

int listScenarios() {
    const auto files = bench::listScenarioFiles();
    if (files.empty())
        return reportError(
                "bench",
                Status(ErrorCode::NotFound,
                       "no scenarios: no bench/*.json under " +
                               std::filesystem::current_path().string() +
                               " (run from the repository root)"));
    for (const auto& file : files) {
        auto scenario = bench::loadScenario(file, false);
        if (scenario)
            std::printf(
                    "%-24s %-7s %s\n",
                    file.stem().c_str(),
                    scenario->kind.c_str(),
                    scenario->title.c_str());
        else
            std::printf(
                    "%-24s %-7s (unreadable: %s)\n",
                    file.stem().c_str(),
                    "?",
                    scenario.status().message().c_str());
    }
    return 0;
}

/** Reads and checks one scenario (its quick variant too, so a typo there shows up now). */
Result<bench::BenchRun> prepare(const std::string& nameOrPath, bool quick) {
    FF_ASSIGN_OR_RETURN(const std::filesystem::path file, bench::findScenario(nameOrPath));
    FF_ASSIGN_OR_RETURN(const bench::Scenario other, bench::loadScenario(file, !quick));
    FF_RETURN_IF_ERROR(bench::prepareScenario(other).status());
    FF_ASSIGN_OR_RETURN(const bench::Scenario scenario, bench::loadScenario(file, quick));
    return bench::prepareScenario(scenario);
}

int runBench(const BenchArgs& args) {
    if (args.list)
        return listScenarios();
    if (args.scenarios.empty())
        return reportError(
                "bench",
                Status(ErrorCode::InvalidArgument,
                       "name at least one scenario (a bench/*.json file or its name; "
                       "`farfield bench --list` shows them)"));
    if (args.frames < 1)
        return reportError("bench", Status(ErrorCode::InvalidArgument, "--frames must be >= 1"));
    std::vector<std::pair<std::string, bench::BenchRun>> runs;
    for (const std::string& name : args.scenarios) {
        auto run = prepare(name, args.quick);
        if (!run)
            return reportError("bench", run.status());
        runs.emplace_back(name, std::move(*run));
    }
    if (args.check) {
        for (const auto& run : runs)
            std::printf("%s: ok\n", run.first.c_str());
        return 0;
    }
    // The folders first: an unwritable --out fails before hours of benchmarks, not after.
    for (const auto& [flag, folder] : {std::pair{"--out", &args.out}, std::pair{"--work-dir", &args.work}}) {
        if (folder->empty())
            continue; // --work-dir defaults to a folder of the bench's own
        if (const Status ready = prepareOutputFolder(*folder); !ready)
            return reportError("bench", ready.withContext(flag));
    }
    bench::BenchOptions options;
    options.outDir = args.out;
    options.workDir = args.work;
    options.timedFrames = args.frames;
    options.selfExe = selfExecutable();
    for (const auto& [name, run] : runs) {
        options.command =
                "farfield bench " + name + (args.quick ? " --quick" : "") +
                (args.framesOption->count() > 0 ? " --frames " + std::to_string(args.frames) : "");
        if (Status status = run(options); !status)
            return reportError("bench", status.withContext(name));
        std::fprintf(stderr, "bench %s: results in %s\n", name.c_str(), args.out.c_str());
    }
    return 0;
}

} // namespace

CommandRunner addBenchCommand(CLI::App& app) {
    auto args = std::make_shared<BenchArgs>();
    CLI::App* cmd = app.add_subcommand(
            "bench", "Run benchmark scenarios (bench/*.json): CSV, PNG charts, Markdown report");
    cmd->footer(kHelpFooter);
    cmd->add_option("scenario", args->scenarios, "Scenario files, or names of bench/NAME.json");
    cmd->add_flag("--list", args->list, "List the scenarios in bench/ with their kinds and titles");
    cmd->add_flag(
            "--check",
            args->check,
            "Read and check the scenarios (with and without their quick overrides), run nothing");
    cmd->add_option("--out", args->out, "Folder for CSV, charts and reports")
            ->capture_default_str();
    cmd->add_option(
            "--work-dir",
            args->work,
            "Folder for the scene files (default: OUT/scenes, removed afterwards)");
    args->framesOption = cmd->add_option(
                                    "--frames",
                                    args->frames,
                                    "Timed frames per measurement (median, after one warm-up)")
                                 ->capture_default_str();
    cmd->add_flag(
            "--quick",
            args->quick,
            "Apply each scenario's \"quick\" overrides: a smoke run, not results");
    return [args]() { return runBench(*args); };
}

} // namespace ff::viewer
