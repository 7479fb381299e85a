#pragma once

#include <ff/bench/Benchmarks.h>
#include <ff/runtime/Camera.h>
#include <ff/runtime/StreamingSession.h>
#include <ff/storage/Status.h>

#include <nlohmann/json.hpp>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace ff::bench {

/** A CSV table built row by row; cells are written as given. */
class CsvTable {
public:
    explicit CsvTable(std::vector<std::string> columns) : mColumns(std::move(columns)) {}
    void addRow(std::vector<std::string> cells) { mRows.push_back(std::move(cells)); }
    [[nodiscard]] Status write(const std::filesystem::path& path) const;
    /** The same table as Markdown, for reports. */
    std::string markdown() const;
    std::size_t rowCount() const noexcept { return mRows.size(); }

private:
    std::vector<std::string> mColumns;
    std::vector<std::vector<std::string>> mRows;
};

std::string formatNumber(double value, int decimals = 2);

/**
 * The skeleton every benchmark kind runs in: read scenario -> run -> CSV -> charts -> report.
 * Constructing it makes the output folder and the work folder for scene files; the kind then
 * measures, writes its tables (CsvTable::write to output(...)) and composes the report's body;
 * finish() draws the charts (scripts/plot_bench.py KIND CSV), writes OUT/NAME.md (the title
 * and description as its heading, then the body), and removes the work folder if it was the
 * default one.
 */
class ScenarioRun {
public:
    ScenarioRun(const Scenario& scenario, const BenchOptions& options);
    const std::filesystem::path& work() const noexcept { return mWork; }
    /** OUT/NAME followed by `suffix` (e.g. ".csv", "-summary.csv"). */
    std::filesystem::path output(const std::string& suffix) const;
    [[nodiscard]] Status finish(const std::string& chartKind, const std::filesystem::path& chartCsv,
                                const std::string& body);

private:
    const Scenario& mScenario;
    const BenchOptions& mOptions;
    std::filesystem::path mWork;
};

/** A frame at `camera` of width x height with `selection` (default budgets). */
runtime::FrameContext frameAt(
        const runtime::Camera& camera,
        const runtime::SelectionOptions& selection,
        int width,
        int height,
        int supersample = 1);

/** Renders the frame `warmup` times untimed, then `timed` times; returns the last frame with
 *  the median total/select/draw milliseconds in its stats. */
[[nodiscard]] Result<runtime::Frame> timeFrames(
        runtime::StreamingSession& session, const runtime::FrameContext& frame, int warmup, int timed);

/** A JSON object written by a child (a build report, a replay summary); Internal error naming
 *  `what` and the path if the file is missing or not an object. */
[[nodiscard]] Result<nlohmann::json> readJsonObject(const std::filesystem::path& path, const char* what);

/** A finished child process. */
struct ChildRun {
    double seconds = 0.0;
    std::uint64_t peakRssBytes = 0; ///< ru_maxrss
};

/** Runs argv (argv[0] an executable path, no shell) to completion; non-zero exit is an error. */
[[nodiscard]] Result<ChildRun> runChild(const std::vector<std::string>& argv);

/** Runs scripts/plot_bench.py KIND CSV OUTDIR with Debian's matplotlib; a missing script or
 *  interpreter is an error naming what is missing. */
[[nodiscard]] Status plotCharts(const std::string& kind, const std::filesystem::path& csv, const std::filesystem::path& outDir);

} // namespace ff::bench
