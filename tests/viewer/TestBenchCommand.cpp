// `farfield bench SCENARIO` end to end: tiny "views", "path" and "replay" scenarios written by the test
// run through the real binary (CSV rows and columns, charts, report), and scenario mistakes fail
// with messages that name the problem.

#include "FarfieldProcess.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace ff::viewer::test {
namespace {

namespace fs = std::filesystem;

using Row = std::vector<std::string>;

/** A CSV written by `farfield bench` (no quoting: cells never hold commas). */
std::vector<Row> readCsv(const fs::path& path) {
    std::vector<Row> rows;
    std::ifstream in(path);
    std::string line;
    while (std::getline(in, line)) {
        Row row;
        std::stringstream cells(line);
        std::string cell;
        while (std::getline(cells, cell, ','))
            row.push_back(cell);
        if (!line.empty() && line.back() == ',')
            row.emplace_back(); // a trailing empty cell
        rows.push_back(row);
    }
    return rows;
}

std::string readText(const fs::path& path) {
    std::ifstream in(path);
    std::stringstream text;
    text << in.rdbuf();
    return text.str();
}

void writeText(const fs::path& path, const std::string& text) {
    std::ofstream(path) << text;
}

/** The cell of `column` in `row`, by the header's column names. */
std::string cell(const std::vector<Row>& csv, std::size_t row, const std::string& column) {
    for (std::size_t i = 0; i < csv[0].size(); ++i)
        if (csv[0][i] == column)
            return i < csv[row].size() ? csv[row][i] : std::string("<missing cell>");
    return "<no column " + column + ">";
}

/** The current directory for the test's scope (the child farfield inherits it). */
class ScopedCurrentPath {
public:
    explicit ScopedCurrentPath(const fs::path& path)
        : mPrevious(fs::current_path()) {
        fs::current_path(path);
    }
    ~ScopedCurrentPath() { fs::current_path(mPrevious); }
    ScopedCurrentPath(const ScopedCurrentPath&) = delete;
    ScopedCurrentPath& operator=(const ScopedCurrentPath&) = delete;

private:
    fs::path mPrevious;
};

constexpr const char* kViewsScenario = R"({
  "name": "tiny-views",
  "title": "A tiny views scenario",
  "description": "Written by TestBenchCommand.",
  "kind": "views",
  "scene": {"generate": "forest:trees=1"},
  "size": [64, 48],
  "views": [{"label": "d6", "distance": 6, "azimuth": 45, "elevation": 35, "fov": 45}],
  "reference": {"supersample": 2},
  "methods": [
    {"label": "full", "method": "full"},
    {"label": "faces", "method": "hierarchical", "eps": 1, "cube_draw": "faces"}
  ],
  "sweep": {"parameter": "eps", "values": [1, 4]}
})";

// Format 1: with every page resident it reads nothing (format 2 is drawn through the cache);
// until it is ported (issue 16: version 1 is to be refused).
constexpr const char* kPathScenario = R"({
  "name": "tiny-path",
  "title": "A tiny path scenario",
  "kind": "path",
  "build": ["--format", "1"],
  "scene": {"generate": "forest:trees=1"},
  "size": [64, 48],
  "path": {"generator": "orbit", "frames": 3},
  "methods": [
    {"label": "faces", "eps": 1, "cube_draw": "faces"},
    {"label": "coarse", "eps": 8, "cube_draw": "points", "cube_anisotropy": 0.5}
  ]
})";

TEST(BenchCommandTest, ViewsScenarioWritesOneRowPerMeasurementChartsAndReport) {
    const fs::path dir = freshTestDir();
    writeText(dir / "tiny-views.json", kViewsScenario);
    const fs::path out = dir / "out";
    const ProcessResult r = runFarfield(
            {"bench", (dir / "tiny-views.json").string(), "--out", out.string(), "--frames", "1"},
            dir);
    ASSERT_EQ(r.exitCode, 0) << r.describe();

    const std::vector<Row> csv = readCsv(out / "tiny-views.csv");
    ASSERT_FALSE(csv.empty());
    const Row expectedColumns = {
            "view",
            "method",
            "selection",
            "eps",
            "cube_draw",
            "cube_anisotropy",
            "sweep_parameter",
            "sweep_value",
            "width",
            "height",
            "frame_ms",
            "select_ms",
            "draw_ms",
            "triangles",
            "cubes",
            "psnr_srgb",
            "ssim",
            "holes_fraction",
            "over_coverage_fraction",
            "reference_covered_pixels",
            "scene_triangles",
            "scene_file_bytes",
            "representation",
            "stand_ins",
            "splat_sets",
            "splats",
            "splat_size"};
    EXPECT_EQ(csv[0], expectedColumns);
    // full once (not swept), faces at eps 1 and 4.
    ASSERT_EQ(csv.size(), 4u);
    EXPECT_EQ(cell(csv, 1, "method"), "full");
    EXPECT_EQ(cell(csv, 1, "sweep_value"), "");
    EXPECT_EQ(cell(csv, 2, "method"), "faces");
    EXPECT_EQ(cell(csv, 2, "sweep_value"), "1");
    EXPECT_EQ(cell(csv, 3, "sweep_value"), "4");
    EXPECT_EQ(cell(csv, 3, "eps"), "4.000");
    for (std::size_t row = 1; row < csv.size(); ++row) {
        SCOPED_TRACE("row " + std::to_string(row));
        EXPECT_EQ(csv[row].size(), expectedColumns.size());
        EXPECT_EQ(cell(csv, row, "view"), "d6");
        EXPECT_EQ(cell(csv, row, "width"), "64");
        EXPECT_GT(std::stod(cell(csv, row, "frame_ms")), 0.0);
        EXPECT_GT(std::stod(cell(csv, row, "psnr_srgb")), 10.0);
        EXPECT_GT(std::stoull(cell(csv, row, "reference_covered_pixels")), 0u);
        EXPECT_GT(std::stoull(cell(csv, row, "scene_triangles")), 50'000u);
    }
    // The coarser setting draws fewer triangles.
    EXPECT_LT(std::stoull(cell(csv, 3, "triangles")), std::stoull(cell(csv, 2, "triangles")));

    EXPECT_TRUE(fs::is_regular_file(out / "tiny-views.png"));
    EXPECT_TRUE(fs::is_regular_file(out / "tiny-views-sweep.png"));
    const std::string md = readText(out / "tiny-views.md");
    EXPECT_NE(md.find("# A tiny views scenario"), std::string::npos) << md;
    EXPECT_NE(md.find("Written by TestBenchCommand."), std::string::npos) << md;
    EXPECT_NE(md.find("farfield bench " + (dir / "tiny-views.json").string()), std::string::npos)
            << md;
    EXPECT_NE(md.find("](tiny-views.png)"), std::string::npos) << md;
    EXPECT_NE(md.find("](tiny-views-sweep.png)"), std::string::npos) << md;
    EXPECT_FALSE(fs::exists(out / "scenes")) << "the default work folder is removed";
}

TEST(BenchCommandTest, PathScenarioWritesPerFrameAndSummaryCsvChartAndReport) {
    const fs::path dir = freshTestDir();
    writeText(dir / "tiny-path.json", kPathScenario);
    const fs::path out = dir / "out";
    const ProcessResult r =
            runFarfield({"bench", (dir / "tiny-path.json").string(), "--out", out.string()}, dir);
    ASSERT_EQ(r.exitCode, 0) << r.describe();

    const std::vector<Row> frames = readCsv(out / "tiny-path.csv");
    ASSERT_FALSE(frames.empty());
    // The method, the streaming session's telemetry (runtime/FrameTelemetry.h, pinned by
    // FrameTelemetryTest), then the pair's instability.
    ASSERT_GE(frames[0].size(), 8u);
    EXPECT_EQ(Row(frames[0].begin(), frames[0].begin() + 6),
              (Row{"method", "frame", "time_s", "frame_ms", "select_ms", "draw_ms"}));
    EXPECT_EQ(frames[0].back(), "instability");
    for (const char* column : {"psnr_db", "bytes_read_total", "nodes_deferred", "triangles", "cubes"})
        EXPECT_NE(std::find(frames[0].begin(), frames[0].end(), column), frames[0].end()) << column;
    ASSERT_EQ(frames.size(), 1u + 2 * 3); // two methods, three frames each
    EXPECT_EQ(cell(frames, 1, "method"), "faces");
    EXPECT_EQ(cell(frames, 1, "frame"), "0");
    EXPECT_EQ(cell(frames, 1, "instability"), "") << "no pair before the first frame";
    EXPECT_EQ(cell(frames, 6, "method"), "coarse");
    EXPECT_EQ(cell(frames, 6, "frame"), "2");
    EXPECT_GE(std::stod(cell(frames, 6, "instability")), 0.0);

    const std::vector<Row> summary = readCsv(out / "tiny-path-summary.csv");
    ASSERT_EQ(summary.size(), 3u);
    ASSERT_GE(summary[0].size(), 15u);
    EXPECT_EQ(
            Row(summary[0].begin(), summary[0].begin() + 15),
            (Row{"method",
                 "selection",
                 "eps",
                 "cube_draw",
                 "cube_anisotropy",
                 "frames",
                 "mean_instability",
                 "p95_instability",
                 "max_instability",
                 "median_psnr",
                 "min_psnr",
                 "p50_ms",
                 "p99_ms",
                 "debt_frames",
                 "bytes_read"}));
    EXPECT_EQ(cell(summary, 1, "method"), "faces");
    EXPECT_EQ(cell(summary, 2, "method"), "coarse");
    EXPECT_EQ(cell(summary, 2, "cube_draw"), "points");
    EXPECT_EQ(cell(summary, 2, "cube_anisotropy"), "0.50");
    EXPECT_EQ(cell(summary, 2, "frames"), "3");
    EXPECT_GE(
            std::stod(cell(summary, 2, "max_instability")),
            std::stod(cell(summary, 2, "mean_instability")));

    EXPECT_EQ(cell(summary, 1, "bytes_read"), "0") << "every page resident: nothing read";
    EXPECT_EQ(cell(summary, 1, "occlusion"), "off");
    EXPECT_EQ(cell(summary, 1, "mean_queries"), "0.0");

    EXPECT_TRUE(fs::is_regular_file(out / "tiny-path.png"));
    EXPECT_FALSE(fs::exists(out / "tiny-path-bytes.png")) << "no bytes-read chart without streaming";
    const std::string md = readText(out / "tiny-path.md");
    EXPECT_NE(md.find("# A tiny path scenario"), std::string::npos) << md;
    EXPECT_NE(md.find("](tiny-path.png)"), std::string::npos) << md;
}

// Occlusion culling along a walk through a small city: the methods' Table-1 columns.
TEST(BenchCommandTest, PathScenarioComparesOcclusionWithFrustumCullingAlongAWalk) {
    const fs::path dir = freshTestDir();
    writeText(dir / "tiny-city.json", R"({
  "title": "A tiny city walk",
  "kind": "path",
  "scene": {"generate": "city:blocks=3"},
  "size": [80, 60],
  "path": {"generator": "walk", "frames": 4, "legs": [[[10, 1.7, 30], [10, 1.7, -30]]]},
  "methods": [
    {"label": "vfc", "eps": 0},
    {"label": "occlusion", "eps": 0, "occlusion": true},
    {"label": "no coherence", "eps": 0, "occlusion": true, "coherence": false}
  ]
})");
    const fs::path out = dir / "out";
    const ProcessResult r =
            runFarfield({"bench", (dir / "tiny-city.json").string(), "--out", out.string()}, dir);
    ASSERT_EQ(r.exitCode, 0) << r.describe();
    const std::vector<Row> summary = readCsv(out / "tiny-city-summary.csv");
    ASSERT_EQ(summary.size(), 4u);
    EXPECT_EQ(cell(summary, 1, "occlusion"), "off");
    EXPECT_EQ(cell(summary, 2, "occlusion"), "on");
    EXPECT_EQ(cell(summary, 2, "coherence"), "on");
    EXPECT_EQ(cell(summary, 3, "coherence"), "off");
    EXPECT_EQ(std::stod(cell(summary, 1, "mean_queries")), 0.0);
    EXPECT_GT(std::stod(cell(summary, 2, "mean_queries")), 0.0);
    // From the street, the furnished interiors are hidden behind the facades.
    EXPECT_LT(std::stod(cell(summary, 2, "mean_triangles")), 0.5 * std::stod(cell(summary, 1, "mean_triangles")));
    EXPECT_GT(std::stod(cell(summary, 2, "mean_nodes_occluded")), 0.0);
    EXPECT_GT(std::stod(cell(summary, 1, "mean_render_rate")), std::stod(cell(summary, 2, "mean_render_rate")));
    const std::vector<Row> frames = readCsv(out / "tiny-city.csv");
    for (const char* column : {"occlusion_ms", "occlusion_queries", "queries_waited", "render_rate"})
        EXPECT_NE(std::find(frames[0].begin(), frames[0].end(), column), frames[0].end()) << column;
}

// Through a cold cache each method's reads add up frame by frame, and the report charts its
// error against them.
TEST(BenchCommandTest, StreamingPathScenarioChartsErrorAgainstBytesRead) {
    const fs::path dir = freshTestDir();
    std::string scenario = kPathScenario;
    scenario.replace(scenario.rfind('}'), 1, R"(, "cache_mb": 4, "uploads_per_frame": 4})");
    writeText(dir / "tiny-path.json", scenario);
    const fs::path out = dir / "out";
    const ProcessResult r =
            runFarfield({"bench", (dir / "tiny-path.json").string(), "--out", out.string()}, dir);
    ASSERT_EQ(r.exitCode, 0) << r.describe();

    const std::vector<Row> frames = readCsv(out / "tiny-path.csv");
    ASSERT_EQ(frames.size(), 1u + 2 * 3);
    const std::vector<Row> summary = readCsv(out / "tiny-path-summary.csv");
    ASSERT_EQ(summary.size(), 3u);
    for (std::size_t method = 0; method < 2; ++method) {
        SCOPED_TRACE("method " + std::to_string(method));
        std::uint64_t previous = 0;
        for (std::size_t f = 0; f < 3; ++f) {
            const std::uint64_t read = std::stoull(cell(frames, 1 + method * 3 + f, "bytes_read_total"));
            EXPECT_GE(read, previous) << "cumulative";
            previous = read;
        }
        EXPECT_GT(previous, 0u);
        EXPECT_EQ(cell(summary, 1 + method, "bytes_read"), std::to_string(previous));
    }
    EXPECT_TRUE(fs::is_regular_file(out / "tiny-path-bytes.png"));
    EXPECT_NE(readText(out / "tiny-path.md").find("](tiny-path-bytes.png)"), std::string::npos);
}

// A frame's peak memory, measured in a child `farfield render`, against a limit.
TEST(BenchCommandTest, RenderScenarioMeasuresTheFramesPeakMemoryAgainstItsLimit) {
    const fs::path dir = freshTestDir();
    writeText(dir / "tiny-render.json", R"({
  "name": "tiny-render",
  "title": "A tiny render scenario",
  "kind": "render",
  "scene": {"generate": "molecule:spheres=200"},
  "size": [64, 48],
  "views": [{"label": "near", "flags": ["--distance", "1.5"]}, {"label": "far", "flags": ["--distance", "30"]}],
  "rss_limit": "4GiB"
})");
    const fs::path out = dir / "out";
    const ProcessResult r = runFarfield({"bench", (dir / "tiny-render.json").string(), "--out", out.string()}, dir);
    ASSERT_EQ(r.exitCode, 0) << r.describe();
    const std::vector<Row> rows = readCsv(out / "tiny-render.csv");
    ASSERT_EQ(rows.size(), 3u);
    for (std::size_t i = 1; i < rows.size(); ++i) {
        EXPECT_GT(std::stoull(cell(rows, i, "peak_rss_bytes")), 1u << 20);
        EXPECT_EQ(cell(rows, i, "rss_limit_bytes"), std::to_string(4ull << 30));
        EXPECT_EQ(cell(rows, i, "within_limit"), "yes");
        EXPECT_GT(std::stoull(cell(rows, i, "nodes_visited")), 0u);
    }
    EXPECT_EQ(cell(rows, 1, "view"), "near");
    EXPECT_GT(std::stoull(cell(rows, 1, "triangles_drawn")), std::stoull(cell(rows, 2, "triangles_drawn")))
            << "the flags reach the child: nearer draws more";
    EXPECT_TRUE(fs::is_regular_file(out / "tiny-render.png"));
    EXPECT_NE(readText(out / "tiny-render.md").find("| near |"), std::string::npos);
}

// The codec benchmark in miniature: the terrain's v1 leaves (a few triangles each) and the same
// hierarchy cut at subtrees of <= 4096 triangles, encoded as clusters and decoded again: every
// triangle kept, larger leaves store fewer bytes a triangle, both far below v1's file.
TEST(BenchCommandTest, CodecScenarioEncodesTheLeavesOfABuildAndDecodesThemAgain) {
    const fs::path dir = freshTestDir();
    writeText(dir / "tiny-codec.json", R"({
  "name": "tiny-codec",
  "title": "A tiny codec scenario",
  "kind": "codec",
  "scenes": [{"label": "terrain", "generate": "terrain:triangles=20000"}],
  "variants": [{"leaf_triangles": 0}, {"leaf_triangles": 4096}, {"leaf_triangles": 4096, "edge_steps": 64}],
  "decode_seconds": 0.05,
  "page_size": 16384
})");
    const fs::path out = dir / "out";
    const ProcessResult r = runFarfield({"bench", (dir / "tiny-codec.json").string(), "--out", out.string()}, dir);
    ASSERT_EQ(r.exitCode, 0) << r.describe();
    const std::vector<Row> rows = readCsv(out / "tiny-codec.csv");
    ASSERT_EQ(rows.size(), 4u);
    for (std::size_t i = 1; i < rows.size(); ++i) {
        EXPECT_EQ(cell(rows, i, "triangles_kept"), cell(rows, i, "stored_triangles"));
        EXPECT_GT(std::stod(cell(rows, i, "decode_gb_per_s")), 0.0);
        EXPECT_LT(std::stod(cell(rows, i, "bytes_per_triangle")), std::stod(cell(rows, i, "v1_file_bytes_per_triangle")) / 3);
    }
    EXPECT_GT(std::stoull(cell(rows, 1, "leaves")), std::stoull(cell(rows, 2, "leaves")));
    EXPECT_LT(std::stod(cell(rows, 2, "bytes_per_triangle")), std::stod(cell(rows, 1, "bytes_per_triangle")));
    // The v2 estimate adds page slack, records and representations to the clusters' bytes; the
    // hierarchy cut at 4096 triangles has far fewer nodes, so it stays near its clusters.
    for (std::size_t i = 1; i < rows.size(); ++i) {
        const double clusters = std::stod(cell(rows, i, "bytes_per_triangle"));
        const double v2 = std::stod(cell(rows, i, "v2_estimate_bytes_per_triangle"));
        EXPECT_GT(v2, clusters);
        EXPECT_GT(std::stoull(cell(rows, i, "v2_pages")), 1u);
    }
    EXPECT_LT(std::stoull(cell(rows, 2, "v2_nodes")) * 20, std::stoull(cell(rows, 1, "v2_nodes")));
    // A step of a 64th of the median edge: far coarser than 20 bits over the terrain's extent,
    // so fewer bits, a larger error and fewer bytes.
    EXPECT_LT(std::stoi(cell(rows, 3, "grid_bits")), 20);
    EXPECT_GT(std::stod(cell(rows, 3, "max_position_error")), std::stod(cell(rows, 2, "max_position_error")));
    EXPECT_LT(std::stod(cell(rows, 3, "bytes_per_triangle")), std::stod(cell(rows, 2, "bytes_per_triangle")));
    EXPECT_LT(std::stod(cell(rows, 2, "v2_estimate_bytes_per_triangle")), 2 * std::stod(cell(rows, 2, "bytes_per_triangle")));
    EXPECT_TRUE(fs::is_regular_file(out / "tiny-codec.png"));
    EXPECT_NE(readText(out / "tiny-codec.md").find("| terrain |"), std::string::npos);
}

// "build" gives every forest of the ladder its flags: format 2's files are smaller, and an
// instanced tree's cut is format 1's (leaves of 16 triangles; docs/results, "Format 2 paged").
TEST(BenchCommandTest, ForestScenarioBuildsEveryForestWithItsFlags) {
    const fs::path dir = freshTestDir();
    const std::string forest = R"("kind": "forest", "trees": [1, 16], "sizes": [[64, 48]])";
    writeText(dir / "tiny-forest.json",
              "{\"name\": \"tiny-forest\", " + forest + R"(, "build": ["--format", "1"]})");
    writeText(dir / "tiny-forest-v2.json",
              "{\"name\": \"tiny-forest-v2\", " + forest + R"(, "build": ["--format", "2"]})");
    const fs::path out = dir / "out";
    const ProcessResult r = runFarfield(
            {"bench", (dir / "tiny-forest.json").string(), (dir / "tiny-forest-v2.json").string(),
             "--out", out.string(), "--frames", "1"},
            dir);
    ASSERT_EQ(r.exitCode, 0) << r.describe();
    const std::vector<Row> one = readCsv(out / "tiny-forest.csv");
    const std::vector<Row> two = readCsv(out / "tiny-forest-v2.csv");
    ASSERT_EQ(one.size(), 3u);
    ASSERT_EQ(two.size(), 3u);
    for (std::size_t i = 1; i < one.size(); ++i) {
        EXPECT_LT(std::stoull(cell(two, i, "file_bytes")), std::stoull(cell(one, i, "file_bytes")));
        EXPECT_EQ(cell(two, i, "triangles"), cell(one, i, "triangles"));
    }
    EXPECT_LE(std::stod(cell(two, 2, "triangles_drawn")), 1.25 * std::stod(cell(one, 2, "triangles_drawn")));
    EXPECT_NE(readText(out / "tiny-forest-v2.md").find("built with `--format 2`"), std::string::npos);
    EXPECT_NE(readText(out / "tiny-forest.md").find("built with `--format 1`"), std::string::npos);
}

constexpr const char* kReplayScenario = R"({
  "name": "tiny-replay",
  "title": "A tiny replay scenario",
  "kind": "replay",
  "scene": {"generate": "terrain:triangles=20000"},
  "build": ["--memory-budget", "16MiB"],
  "size": [64, 48],
  "path": {"generator": "flythrough", "frames": 6},
  "cache_mb": 2
})";

// The larger-than-RAM benchmark in miniature: build under a budget, replay through a cache far
// smaller than the file, per-frame telemetry within the budget, and no scene file left behind
// in the work folder the user named.
TEST(BenchCommandTest, ReplayScenarioMeasuresBuildAndReplayAndRemovesTheScene) {
    const fs::path dir = freshTestDir();
    writeText(dir / "tiny-replay.json", kReplayScenario);
    const fs::path out = dir / "out";
    const fs::path work = dir / "work";
    const ProcessResult r = runFarfield(
            {"bench", (dir / "tiny-replay.json").string(), "--out", out.string(), "--work-dir", work.string()}, dir);
    ASSERT_EQ(r.exitCode, 0) << r.describe();

    const std::vector<Row> frames = readCsv(out / "tiny-replay.csv");
    ASSERT_EQ(frames.size(), 1u + 6);
    constexpr std::uint64_t kBudget = 2u << 20;
    std::uint64_t bytesRead = 0;
    for (std::size_t row = 1; row < frames.size(); ++row) {
        SCOPED_TRACE("frame " + std::to_string(row - 1));
        EXPECT_EQ(cell(frames, row, "frame"), std::to_string(row - 1));
        EXPECT_LE(std::stoull(cell(frames, row, "resident_bytes")), kBudget);
        bytesRead += std::stoull(cell(frames, row, "bytes_read"));
    }
    EXPECT_GT(bytesRead, 0u);

    std::ifstream summaryFile(out / "tiny-replay-summary.json");
    const nlohmann::json summary = nlohmann::json::parse(summaryFile, nullptr, false);
    ASSERT_TRUE(summary.is_object());
    EXPECT_EQ(summary.value("frames", 0), 6);
    EXPECT_EQ(summary.value("budget_bytes", std::uint64_t{0}), kBudget);
    EXPECT_EQ(summary.value("bytes_read", std::uint64_t{0}), bytesRead);
    EXPECT_LE(summary.value("peak_resident_bytes", ~std::uint64_t{0}), kBudget);

    EXPECT_TRUE(fs::is_regular_file(out / "tiny-replay.png"));
    const std::string md = readText(out / "tiny-replay.md");
    EXPECT_NE(md.find("# A tiny replay scenario"), std::string::npos) << md;
    EXPECT_NE(md.find("farfield build --memory-budget 16MiB"), std::string::npos) << md;
    EXPECT_NE(md.find("| 20000 |"), std::string::npos) << md; // the build row: triangles first
    EXPECT_NE(md.find("](tiny-replay.png)"), std::string::npos) << md;
    ASSERT_TRUE(fs::is_directory(work));
    EXPECT_TRUE(fs::is_empty(work)) << "the scene and its path are removed from --work-dir";
}

TEST(BenchCommandTest, UnknownKeyFailsNamingTheKeyAndTheFile) {
    const fs::path dir = freshTestDir();
    std::string text = kViewsScenario;
    text.replace(text.find("\"eps\": 1,"), 9, "\"epsilon\": 1,");
    writeText(dir / "typo.json", text);
    writeText(dir / "good.json", kPathScenario);
    const ProcessResult r = runFarfield(
            {"bench",
             (dir / "good.json").string(),
             (dir / "typo.json").string(),
             "--out",
             (dir / "out").string()},
            dir);
    EXPECT_TRUE(r.exited && r.exitCode != 0) << r.describe();
    EXPECT_NE(r.err.find("typo.json"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("methods[1]"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("unknown key \"epsilon\""), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir / "out" / "tiny-path.csv"))
            << "nothing runs before every scenario is checked";
}

TEST(BenchCommandTest, BadValueInTheQuickOverridesFailsWithoutQuickToo) {
    const fs::path dir = freshTestDir();
    std::string text = kPathScenario;
    text.insert(text.rfind('}'), R"(, "quick": {"path": {"generator": "spiral"}})");
    writeText(dir / "bad-quick.json", text);
    const ProcessResult r = runFarfield(
            {"bench", (dir / "bad-quick.json").string(), "--out", (dir / "out").string()}, dir);
    EXPECT_TRUE(r.exited && r.exitCode != 0) << r.describe();
    EXPECT_NE(r.err.find("quick overrides"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("path.generator"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("spiral"), std::string::npos) << r.err;
}

TEST(BenchCommandTest, MissingScenarioIsNamedAndTheAvailableOnesListed) {
    const fs::path dir = freshTestDir();
    fs::create_directories(dir / "bench");
    writeText(dir / "bench" / "tiny-views.json", kViewsScenario);
    const ScopedCurrentPath cwd(dir);

    const ProcessResult missing = runFarfield({"bench", "no-such-scenario"}, dir);
    EXPECT_TRUE(missing.exited && missing.exitCode != 0) << missing.describe();
    EXPECT_NE(missing.err.find("\"no-such-scenario\" not found"), std::string::npos) << missing.err;
    EXPECT_NE(missing.err.find("bench/no-such-scenario.json"), std::string::npos) << missing.err;
    EXPECT_NE(missing.err.find("available: tiny-views"), std::string::npos) << missing.err;

    const ProcessResult missingFile = runFarfield({"bench", "elsewhere/none.json"}, dir);
    EXPECT_TRUE(missingFile.exited && missingFile.exitCode != 0) << missingFile.describe();
    EXPECT_NE(missingFile.err.find("no file elsewhere/none.json"), std::string::npos)
            << missingFile.err;

    const ProcessResult list = runFarfield({"bench", "--list"}, dir);
    EXPECT_EQ(list.exitCode, 0) << list.describe();
    EXPECT_NE(list.out.find("tiny-views"), std::string::npos) << list.out;
    EXPECT_NE(list.out.find("A tiny views scenario"), std::string::npos) << list.out;
}

// The committed scenarios (bench/*.json) parse and pass every check, their quick variants too.
TEST(BenchCommandTest, CommittedScenariosAreValid) {
    const fs::path dir = freshTestDir();
    std::vector<std::string> args = {"bench", "--check"};
    for (const auto& entry : fs::directory_iterator(FF_BENCH_DIR))
        if (entry.path().extension() == ".json")
            args.push_back(entry.path().string());
    ASSERT_GE(args.size(), 2u + 4u) << "table2, forest, build and paging at least";
    const ProcessResult r = runFarfield(args, dir);
    EXPECT_EQ(r.exitCode, 0) << r.describe();
    EXPECT_NE(r.out.find("table2.json: ok"), std::string::npos) << r.out;
}

} // namespace
} // namespace ff::viewer::test
