#include "BenchSupport.h"

#include <ff/bench/Benchmarks.h>

#include <sys/resource.h>
#include <sys/wait.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <chrono>
#include <fcntl.h>
#include <unistd.h>

namespace ff::bench {

namespace {

/** The work folder for scene files (options.workDir, else OUT/scenes), created. */
std::filesystem::path workFolder(const BenchOptions& options) {
    const std::filesystem::path work = options.workDir.empty() ? options.outDir / "scenes" : options.workDir;
    std::filesystem::create_directories(work);
    return work;
}

/** Removes the work folder if it was the default one. */
void removeWorkFolder(const BenchOptions& options) {
    if (options.workDir.empty())
        std::filesystem::remove_all(options.outDir / "scenes");
}

} // namespace

Status CsvTable::write(const std::filesystem::path& path) const {
    std::ofstream out(path);
    // RFC 4180: a cell with a comma, quote or line break is quoted, its quotes doubled (labels
    // come from scenario files and may hold anything).
    auto cell = [](const std::string& text) {
        if (text.find_first_of(",\"\n\r") == std::string::npos)
            return text;
        std::string quoted = "\"";
        for (char c : text)
            quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
        return quoted + "\"";
    };
    auto line = [&out, &cell](const std::vector<std::string>& cells) {
        for (std::size_t i = 0; i < cells.size(); ++i)
            out << (i ? "," : "") << cell(cells[i]);
        out << "\n";
    };
    line(mColumns);
    for (const auto& row : mRows)
        line(row);
    if (!out)
        return Status(ErrorCode::IoError, "cannot write " + path.string());
    return Status::ok();
}

std::string CsvTable::markdown() const {
    std::string text = "|";
    for (const std::string& c : mColumns)
        text += " " + c + " |";
    text += "\n|";
    for (std::size_t i = 0; i < mColumns.size(); ++i)
        text += "---|";
    text += "\n";
    for (const auto& row : mRows) {
        text += "|";
        for (const std::string& c : row)
            text += " " + c + " |";
        text += "\n";
    }
    return text;
}

std::string formatNumber(double value, int decimals) {
    char text[64];
    std::snprintf(text, sizeof(text), "%.*f", decimals, value);
    return text;
}

runtime::FrameContext frameAt(
        const runtime::Camera& camera,
        const runtime::SelectionOptions& selection,
        int width,
        int height,
        int supersample) {
    runtime::FrameContext frame;
    frame.camera = camera;
    frame.selection = selection;
    frame.width = width;
    frame.height = height;
    frame.supersample = supersample;
    return frame;
}

Result<runtime::Frame> timeFrames(
        runtime::StreamingSession& session, const runtime::FrameContext& frameContext, int warmup, int timed) {
    for (int i = 0; i < warmup; ++i)
        FF_RETURN_IF_ERROR(session.render(frameContext).status());
    std::vector<double> total, select, draw;
    Result<runtime::Frame> frame = Status(ErrorCode::InvalidArgument, "no timed frame");
    for (int i = 0; i < std::max(timed, 1); ++i) {
        frame = session.render(frameContext);
        if (!frame)
            return frame;
        total.push_back(frame->stats.totalMs);
        select.push_back(frame->stats.selectMs);
        draw.push_back(frame->stats.drawMs);
    }
    auto median = [](std::vector<double> v) {
        std::sort(v.begin(), v.end());
        return v[v.size() / 2];
    };
    frame->stats.totalMs = median(total);
    frame->stats.selectMs = median(select);
    frame->stats.drawMs = median(draw);
    return frame;
}

Result<ChildRun> runChild(const std::vector<std::string>& argv) {
    std::vector<char*> args;
    for (const std::string& a : argv)
        args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    const auto start = std::chrono::steady_clock::now();
    const pid_t pid = fork();
    if (pid < 0)
        return Status(ErrorCode::IoError, "cannot start " + argv[0]);
    if (pid == 0) {
        // Children report through files; their stdout lines would interleave with ours.
        const int devNull = open("/dev/null", O_WRONLY);
        if (devNull >= 0)
            dup2(devNull, STDOUT_FILENO);
        execv(args[0], args.data());
        _exit(127);
    }
    int status = 0;
    rusage usage{};
    wait4(pid, &status, 0, &usage);
    ChildRun run;
    run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    run.peakRssBytes = static_cast<std::uint64_t>(usage.ru_maxrss) * 1024;
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
        std::string command;
        for (const std::string& a : argv)
            command += (command.empty() ? "" : " ") + a;
        const std::string how = WIFEXITED(status) ? "exit status " + std::to_string(WEXITSTATUS(status))
                                : WIFSIGNALED(status) ? "killed by signal " + std::to_string(WTERMSIG(status))
                                                      : "did not finish";
        return Status(ErrorCode::Internal, "failed (" + how + "): " + command);
    }
    return run;
}

Status plotCharts(const std::string& kind, const std::filesystem::path& csv, const std::filesystem::path& outDir) {
    const std::filesystem::path script = std::filesystem::path(FF_SOURCE_DIR) / "scripts" / "plot_bench.py";
    if (!std::filesystem::exists(script))
        return Status(ErrorCode::NotFound, "chart script " + script.string() + " is missing");
    const pid_t pid = fork();
    if (pid < 0)
        return Status(ErrorCode::IoError, "cannot start the chart script");
    if (pid == 0) {
        // Debian's interpreter, where python3-matplotlib lives (a user's PATH may hold another).
        execl("/usr/bin/python3", "python3", script.c_str(), kind.c_str(), csv.c_str(), outDir.c_str(),
              static_cast<char*>(nullptr));
        _exit(127);
    }
    int status = 0;
    waitpid(pid, &status, 0);
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
        return Status(ErrorCode::Internal, "chart script failed (is python3-matplotlib installed?)");
    return Status::ok();
}

ScenarioRun::ScenarioRun(const Scenario& scenario, const BenchOptions& options)
    : mScenario(scenario)
    , mOptions(options) {
    std::filesystem::create_directories(options.outDir);
    mWork = workFolder(options);
}

std::filesystem::path ScenarioRun::output(const std::string& suffix) const {
    return mOptions.outDir / (mScenario.name + suffix);
}

Status ScenarioRun::finish(const std::string& chartKind, const std::filesystem::path& chartCsv, const std::string& body) {
    FF_RETURN_IF_ERROR(plotCharts(chartKind, chartCsv, mOptions.outDir));
    const std::filesystem::path path = output(".md");
    std::ofstream out(path);
    out << "# " << mScenario.title << "\n\n";
    if (!mScenario.description.empty())
        out << mScenario.description << "\n\n";
    out << body;
    out.close();
    if (!out)
        return Status(ErrorCode::IoError, "cannot write " + path.string());
    removeWorkFolder(mOptions);
    return Status::ok();
}

Result<nlohmann::json> readJsonObject(const std::filesystem::path& path, const char* what) {
    std::ifstream in(path);
    nlohmann::json json = nlohmann::json::parse(in, nullptr, false);
    if (!json.is_object())
        return Status(ErrorCode::Internal, std::string("unreadable ") + what + " " + path.string());
    return json;
}

} // namespace ff::bench
