#pragma once

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

private:
    std::vector<std::string> mColumns;
    std::vector<std::vector<std::string>> mRows;
};

std::string formatNumber(double value, int decimals = 2);

/** A scenario's Markdown report, OUTDIR/NAME.md: opened with its title (and description, if
 *  any) as the heading; close() says whether everything reached the disk. */
class ReportFile {
public:
    ReportFile(const std::filesystem::path& outDir, const std::string& name, const std::string& title,
               const std::string& description);
    std::ostream& stream() noexcept { return mOut; }
    /** IoError naming the file if any write failed. */
    [[nodiscard]] Status close();

private:
    std::filesystem::path mPath;
    std::ofstream mOut;
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

/** Builds a generator's scene (e.g. "forest:trees=16") into `path` with a 2 GiB budget. */
[[nodiscard]] Status buildGenerated(const std::string& spec, const std::filesystem::path& path);

/** Runs scripts/plot_bench.py KIND CSV OUTDIR with Debian's matplotlib; a missing script or
 *  interpreter is an error naming what is missing. */
[[nodiscard]] Status plotCharts(const std::string& kind, const std::filesystem::path& csv, const std::filesystem::path& outDir);

} // namespace ff::bench
