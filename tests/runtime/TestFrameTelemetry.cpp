// The per-frame telemetry's schema is defined once (runtime/src/FrameTelemetry.cpp) and only
// ever grows at its end: this pins every column that exists, in order, so renaming, removing or
// reordering one fails here, while adding one at the end means adding it to the list below.

#include <ff/runtime/FrameTelemetry.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace ff::runtime {
namespace {

const std::vector<std::string> kPinnedColumns = {
        // `replay --csv` before issue 14, unchanged.
        "frame",
        "time_s",
        "frame_ms",
        "select_ms",
        "draw_ms",
        "requests",
        "hits",
        "misses",
        "bytes_read",
        "resident_bytes",
        "gpu_resident_bytes",
        "in_flight",
        "evicted",
        "dropped",
        "nodes_deferred",
        "triangles",
        "cubes",
        "stalled",
        "psnr_db",
        "holes",
        "node_page_bytes",
        "geometry_page_bytes",
        // Added by issue 14.
        "pump_ms",
        "prefetch_ms",
        "bytes_read_total",
        "cancelled",
        "refused",
        "no_room",
        "nodes_visited",
        "nodes_culled",
        "nodes_occluded",
        "instances_entered",
        "geometry_draws",
        "pages_uploaded",
        "uploads_refused",
        "pages_missing",
        // Added by issue 15.
        "occlusion_ms",
        "occlusion_queries",
        "queries_waited",
        "render_rate",
        // Added by issue 16.
        "pages_decoded",
        "decode_ms",
        "decoded_held_bytes",
        "pages_decoded_on_draw",
        // Added by issue 17.
        "stand_ins",
        "splat_sets",
        "splats",
        "fallbacks",
        // Added by issue 15, once format 2's records carried subtree counts.
        "triangles_occluded",
        // Added by issue 15, once frames could go untested where culling did not pay.
        "occlusion_skipped"};

TEST(FrameTelemetryTest, ColumnsAreThePinnedOnesInOrder) {
    EXPECT_EQ(telemetryColumnNames(), kPinnedColumns);
    for (const TelemetryColumn& column : telemetryColumns())
        EXPECT_GT(std::string(column.meaning).size(), 5u) << column.name << " says what it means";
}

TEST(FrameTelemetryTest, CsvCellsAndJsonKeysFollowTheColumns) {
    FrameTelemetry t;
    t.frame = 7;
    t.timeSeconds = 0.25;
    t.frameMs = 12.5;
    t.stats.trianglesDrawn = 1234;
    t.stats.nodesOccluded = 3;
    t.bytesRead = 65536;
    t.stalled = true;
    const std::vector<std::string> cells = telemetryCsvCells(t);
    ASSERT_EQ(cells.size(), kPinnedColumns.size());
    const auto cell = [&](const std::string& name) {
        for (std::size_t i = 0; i < kPinnedColumns.size(); ++i)
            if (kPinnedColumns[i] == name)
                return cells[i];
        return std::string("?");
    };
    EXPECT_EQ(cell("frame"), "7");
    EXPECT_EQ(cell("time_s"), "0.25");
    EXPECT_EQ(cell("frame_ms"), "12.5");
    EXPECT_EQ(cell("triangles"), "1234");
    EXPECT_EQ(cell("nodes_occluded"), "3");
    EXPECT_EQ(cell("bytes_read"), "65536");
    EXPECT_EQ(cell("stalled"), "1");
    EXPECT_EQ(cell("psnr_db"), "") << "not measured";
    EXPECT_EQ(cell("holes"), "") << "not measured";

    const nlohmann::ordered_json row = nlohmann::ordered_json::parse(telemetryJson(t));
    ASSERT_EQ(row.size(), kPinnedColumns.size());
    std::size_t i = 0;
    for (auto it = row.begin(); it != row.end(); ++it, ++i)
        EXPECT_EQ(it.key(), kPinnedColumns[i]) << "JSON keys in column order";
    EXPECT_EQ(row["stalled"], true);
    EXPECT_TRUE(row["psnr_db"].is_null());
    EXPECT_EQ(row["triangles"], 1234);
}

// docs/telemetry.md lists every column, in order, as "| N | `name` |".
TEST(FrameTelemetryTest, TheDocumentationListsEveryColumnInOrder) {
    std::ifstream in(std::string(FF_DOCS_DIR) + "/telemetry.md");
    ASSERT_TRUE(in) << FF_DOCS_DIR << "/telemetry.md";
    std::stringstream text;
    text << in.rdbuf();
    for (std::size_t i = 0; i < kPinnedColumns.size(); ++i) {
        const std::string row = "| " + std::to_string(i + 1) + " | `" + kPinnedColumns[i] + "` |";
        EXPECT_NE(text.str().find(row), std::string::npos) << row;
    }
}

// Identical images score infinite PSNR: a measurement, kept as "inf" in CSV; JSON has no
// infinity and says null.
TEST(FrameTelemetryTest, InfinitePsnrIsInfInCsvAndNullInJson) {
    FrameTelemetry t;
    t.psnrDb = INFINITY;
    t.holes = 0;
    const std::vector<std::string> cells = telemetryCsvCells(t);
    EXPECT_EQ(cells[18], "inf");
    EXPECT_EQ(cells[19], "0");
    const nlohmann::json row = nlohmann::json::parse(telemetryJson(t));
    EXPECT_TRUE(row["psnr_db"].is_null());
    EXPECT_EQ(row["holes"], 0);
}

} // namespace
} // namespace ff::runtime
