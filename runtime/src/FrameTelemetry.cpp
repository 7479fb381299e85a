#include <ff/runtime/FrameTelemetry.h>

#include <nlohmann/json.hpp>

#include <array>
#include <charconv>
#include <cmath>
#include <functional>

namespace ff::runtime {

namespace {

/** A cell: a count, a real, a flag, or nothing measured. */
struct Value {
    enum class Kind { Count, Real, Flag, Missing } kind = Kind::Missing;
    std::uint64_t count = 0;
    double real = 0.0;
};

Value count(std::uint64_t v) {
    return {Value::Kind::Count, v, 0.0};
}
// Infinity is a measurement (PSNR of identical images): "inf" in CSV, null in JSON. NaN is not.
Value real(double v) {
    return std::isnan(v) ? Value{} : Value{Value::Kind::Real, 0, v};
}
Value flag(bool v) {
    return {Value::Kind::Flag, v ? 1u : 0u, 0.0};
}

struct Column {
    TelemetryColumn column;
    std::function<Value(const FrameTelemetry&)> read;
};

// The schema. Append only: readers (scripts/plot_bench.py, users' notebooks) index by name, and
// tests/runtime/TestFrameTelemetry.cpp pins the order of what exists.
const std::vector<Column>& columns() {
    using T = const FrameTelemetry&;
    static const std::vector<Column> table = {
            {{"frame", "frame index since the session opened"},
             [](T t) { return count(static_cast<std::uint64_t>(t.frame)); }},
            {{"time_s", "the frame's time (camera path time), seconds"},
             [](T t) { return real(t.timeSeconds); }},
            {{"frame_ms", "the whole frame, wall clock"}, [](T t) { return real(t.frameMs); }},
            {{"select_ms", "traversal, less the batches drawn meanwhile"},
             [](T t) { return real(t.stats.selectMs); }},
            {{"draw_ms", "uploads, draw calls and the GPU until done"},
             [](T t) { return real(t.stats.drawMs); }},
            {{"requests", "page requests queued"}, [](T t) { return count(t.requests); }},
            {{"hits", "page lookups found resident"}, [](T t) { return count(t.hits); }},
            {{"misses", "page lookups not resident"}, [](T t) { return count(t.misses); }},
            {{"bytes_read", "bytes read from the page source"},
             [](T t) { return count(t.bytesRead); }},
            {{"resident_bytes", "resident page bytes at the frame's end"},
             [](T t) { return count(t.residentBytes); }},
            {{"gpu_resident_bytes", "geometry page bytes in the GPU arena"},
             [](T t) { return count(t.gpuResidentBytes); }},
            {{"in_flight", "requests queued or being read at the frame's end"},
             [](T t) { return count(t.inFlight); }},
            {{"evicted", "pages evicted"}, [](T t) { return count(t.evicted); }},
            {{"dropped", "finished reads that did not fit the budget"},
             [](T t) { return count(t.dropped); }},
            {{"nodes_deferred", "cells drawn coarser than the ε rule wanted (debt)"},
             [](T t) { return count(t.stats.nodesDeferred); }},
            {{"triangles", "triangles drawn"}, [](T t) { return count(t.stats.trianglesDrawn); }},
            {{"cubes", "color cubes drawn"}, [](T t) { return count(t.stats.cubesDrawn); }},
            {{"stalled", "the frame waited for pages (--sync)"},
             [](T t) { return flag(t.stalled); }},
            {{"psnr_db", "PSNR (sRGB) against the reference, when measured"},
             [](T t) { return t.psnrDb ? real(*t.psnrDb) : Value{}; }},
            {{"holes", "pixels the reference covers and the frame does not, when measured"},
             [](T t) { return t.holes ? count(*t.holes) : Value{}; }},
            {{"node_page_bytes", "node page bytes the frame used"},
             [](T t) { return count(t.nodePageBytes); }},
            {{"geometry_page_bytes", "geometry page bytes the frame used"},
             [](T t) { return count(t.geometryPageBytes); }},
            // Added by issue 14.
            {{"pump_ms", "installing finished reads before the frame"},
             [](T t) { return real(t.pumpMs); }},
            {{"prefetch_ms", "the traversal for the camera ahead"},
             [](T t) { return real(t.prefetchMs); }},
            {{"bytes_read_total", "bytes read since the session opened"},
             [](T t) { return count(t.bytesReadTotal); }},
            {{"cancelled", "queued requests cancelled"}, [](T t) { return count(t.cancelled); }},
            {{"refused", "requests refused: too many in flight"},
             [](T t) { return count(t.refused); }},
            {{"no_room", "requests not queued: no room in the budget"},
             [](T t) { return count(t.noRoom); }},
            {{"nodes_visited", "node records the traversal read"},
             [](T t) { return count(t.stats.nodesVisited); }},
            {{"nodes_culled", "nodes outside the frustum"},
             [](T t) { return count(t.stats.nodesCulled); }},
            {{"nodes_occluded", "nodes an occlusion test found hidden"},
             [](T t) { return count(t.stats.nodesOccluded); }},
            {{"instances_entered", "instances refined into their prototype"},
             [](T t) { return count(t.stats.instancesEntered); }},
            {{"geometry_draws", "geometry draw commands"},
             [](T t) { return count(t.stats.geometryDraws); }},
            {{"pages_uploaded", "geometry pages uploaded to the GPU"},
             [](T t) { return count(t.stats.pagesUploaded); }},
            {{"uploads_refused", "geometry pages over the GPU upload budget, or not decoded yet"},
             [](T t) { return count(t.stats.uploadsRefused); }},
            {{"pages_missing", "page lookups that found no usable page"},
             [](T t) { return count(t.stats.pagesMissing); }},
            {{"occlusion_ms", "issuing occlusion tests and reading their answers"},
             [](T t) { return real(t.stats.occlusionMs); }},
            {{"occlusion_queries", "occlusion tests issued (a multiquery once)"},
             [](T t) { return count(t.stats.occlusionQueries); }},
            {{"queries_waited", "occlusion answers the traversal waited for"},
             [](T t) { return count(t.stats.queriesWaited); }},
            {{"render_rate", "triangles drawn, % of the scene's (instances counted)"},
             [](T t) { return real(t.renderRatePercent); }},
            // Added by issue 16 (format 2's decode stage, between the cache and the GPU).
            {{"pages_decoded", "format 2 pages decoded for upload"},
             [](T t) { return count(t.pagesDecoded); }},
            {{"decode_ms", "decode threads' time spent on them"},
             [](T t) { return real(t.decodeMs); }},
            {{"decoded_held_bytes", "decoded bytes waiting for upload at the frame's end"},
             [](T t) { return count(t.decodedHeldBytes); }},
            {{"pages_decoded_on_draw", "pages decoded again on the render thread (arena too small)"},
             [](T t) { return count(t.stats.pagesDecodedOnDraw); }},
            // Added by issue 17.
            {{"stand_ins", "cells drawn as their simplified stand-in"},
             [](T t) { return count(t.stats.standInsDrawn); }},
            {{"splat_sets", "cells drawn as their splats"}, [](T t) { return count(t.stats.splatSetsDrawn); }},
            {{"splats", "splats drawn (points)"}, [](T t) { return count(t.stats.splatsDrawn); }},
            {{"fallbacks", "cells drawn as the nearest kept kind to a forced one"},
             [](T t) { return count(t.stats.representationFallbacks); }},
            // Added by issue 15 later, once format 2's records carried subtree counts.
            {{"triangles_occluded", "triangles below the nodes a test found hidden (format 2); the oracle: the frustum-culled frame's triangles it left out"},
             [](T t) { return count(t.stats.trianglesOccluded); }},
            // Added by issue 15, once frames could go untested where culling did not pay.
            {{"occlusion_skipped", "1: drawn without occlusion tests, as the last tested frame hid too little"},
             [](T t) { return count(t.stats.occlusionSkipped); }},
    };
    return table;
}

std::string csvCell(const Value& v) {
    switch (v.kind) {
    case Value::Kind::Count:
    case Value::Kind::Flag:
        return std::to_string(v.count);
    case Value::Kind::Real: {
        std::array<char, 32> text{};
        const auto end = std::to_chars(text.data(), text.data() + text.size(), v.real).ptr;
        return std::string(text.data(), end);
    }
    case Value::Kind::Missing:
        break;
    }
    return {};
}

nlohmann::json jsonValue(const Value& v) {
    switch (v.kind) {
    case Value::Kind::Count:
        return v.count;
    case Value::Kind::Real:
        return std::isfinite(v.real) ? nlohmann::json(v.real) : nlohmann::json(nullptr);
    case Value::Kind::Flag:
        return v.count != 0;
    case Value::Kind::Missing:
        break;
    }
    return nullptr;
}

} // namespace

const std::vector<TelemetryColumn>& telemetryColumns() {
    static const std::vector<TelemetryColumn> names = [] {
        std::vector<TelemetryColumn> out;
        for (const Column& c : columns())
            out.push_back(c.column);
        return out;
    }();
    return names;
}

std::vector<std::string> telemetryColumnNames() {
    std::vector<std::string> names;
    for (const Column& c : columns())
        names.emplace_back(c.column.name);
    return names;
}

std::vector<std::string> telemetryCsvCells(const FrameTelemetry& telemetry) {
    std::vector<std::string> cells;
    for (const Column& c : columns())
        cells.push_back(csvCell(c.read(telemetry)));
    return cells;
}

std::string telemetryJson(const FrameTelemetry& telemetry) {
    nlohmann::ordered_json row = nlohmann::ordered_json::object();
    for (const Column& c : columns())
        row[c.column.name] = jsonValue(c.read(telemetry));
    return row.dump();
}

} // namespace ff::runtime
