#include "Commands.h"
#include "bench/Benchmarks.h"

#include <climits>
#include <memory>
#include <string>
#include <unistd.h>

namespace ff::viewer {

namespace {

std::string selfExecutable() {
    char path[PATH_MAX];
    const ssize_t n = readlink("/proc/self/exe", path, sizeof(path) - 1);
    return n > 0 ? std::string(path, static_cast<std::size_t>(n)) : std::string("farfield");
}

} // namespace

CommandRunner addBenchCommand(CLI::App& app) {
    auto options = std::make_shared<bench::BenchOptions>();
    auto which = std::make_shared<std::string>();
    auto out = std::make_shared<std::string>("docs/results");
    auto work = std::make_shared<std::string>();
    CLI::App* cmd = app.add_subcommand("bench", "Benchmarks with CSV, PNG charts and a Markdown report");
    cmd->add_option("benchmark", *which,
                    "table2 (Chamberlain Table 2), forest (1..16384 trees), build (terrain ladder), paging "
                    "(working set, teleports)")
            ->required()
            ->check(CLI::IsMember({"table2", "forest", "build", "paging"}));
    cmd->add_option("--out", *out, "Folder for CSV, charts and the report")->capture_default_str();
    cmd->add_option("--work-dir", *work, "Folder for the scene files (default: OUT/scenes, removed afterwards)");
    cmd->add_option("--frames", options->timedFrames, "Timed frames per measurement (median)")->capture_default_str();
    cmd->add_flag("--quick", options->quick, "Smaller ladders: a smoke run, not results");
    return [options, which, out, work]() {
        options->outDir = *out;
        options->workDir = *work;
        options->selfExe = selfExecutable();
        Status status = Status::ok();
        if (*which == "table2")
            status = bench::runTable2(*options);
        else if (*which == "forest")
            status = bench::runForest(*options);
        else if (*which == "paging")
            status = bench::runPaging(*options);
        else
            status = bench::runBuild(*options);
        if (!status)
            return reportError("bench", status);
        std::fprintf(stderr, "bench %s: results in %s\n", which->c_str(), out->c_str());
        return 0;
    };
}

} // namespace ff::viewer
