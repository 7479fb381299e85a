#pragma once

#include <ff/runtime/FrameStats.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace ff::runtime {

/**
 * One frame of a streaming session as users and machines read it (`replay --csv/--json`, the
 * path benchmarks, the HUD): the traversal's and renderer's FrameStats, the page cache's
 * counters for the frame, and what the caller measured against a reference. The CSV columns and
 * JSON keys come from one table in FrameTelemetry.cpp (telemetryColumns()); columns are only
 * ever added to its end.
 *
 * Times: frame_ms is the whole frame on the wall clock; pump_ms (installing finished reads),
 * select_ms (traversal), occlusion_ms (issuing occlusion tests and reading their answers),
 * draw_ms (uploads, draw calls, the GPU until done) and prefetch_ms (the traversal for the camera
 * ahead) are its parts; the rest is the image's readback. Later parts of a frame get a column of
 * their own and leave the others' meaning alone.
 */
struct FrameTelemetry {
    std::int64_t frame = 0;   ///< frames since the session opened, from 0
    double timeSeconds = 0.0; ///< FrameContext::timeSeconds (a camera path's time)
    double frameMs = 0.0;
    double pumpMs = 0.0;
    double prefetchMs = 0.0;
    FrameStats stats;
    // The page cache during this frame (all 0 when every page is mapped).
    std::uint64_t requests = 0;
    std::uint64_t hits = 0;
    std::uint64_t misses = 0;
    std::uint64_t bytesRead = 0;
    std::uint64_t bytesReadTotal = 0; ///< since the session opened
    std::uint64_t residentBytes = 0;  ///< at the frame's end
    std::uint64_t inFlight = 0;       ///< at the frame's end
    std::uint64_t evicted = 0;
    std::uint64_t dropped = 0;
    std::uint64_t cancelled = 0;
    std::uint64_t refused = 0;
    std::uint64_t noRoom = 0;
    std::uint64_t gpuResidentBytes = 0;
    // Format 2's decode stage during this frame (all 0 for format 1).
    std::uint64_t pagesDecoded = 0;
    double decodeMs = 0.0; ///< decode threads' time, summed over threads
    std::uint64_t decodedHeldBytes = 0; ///< at the frame's end
    /** Page bytes the frame used (found Ready), by type: its working set. */
    std::uint64_t nodePageBytes = 0;
    std::uint64_t geometryPageBytes = 0;
    /** Triangles drawn as a share of the scene's, instances counted (Meißner et al.'s "render
     *  rate"), in %. */
    double renderRatePercent = 0.0;
    /** The frame waited for pages (a --sync session's frames with debt). */
    bool stalled = false;
    /** Against a reference image, when the caller measured it. */
    std::optional<double> psnrDb;
    std::optional<std::uint64_t> holes;
};

/** A column of the telemetry: its CSV header / JSON key and what it means. */
struct TelemetryColumn {
    const char* name;
    const char* meaning;
};

/** Every column, in CSV order. */
const std::vector<TelemetryColumn>& telemetryColumns();
/** telemetryColumns()' names. */
std::vector<std::string> telemetryColumnNames();
/** One CSV cell per column (numbers round-trip exactly; an unmeasured value is empty). */
std::vector<std::string> telemetryCsvCells(const FrameTelemetry& telemetry);
/** The frame as one JSON object keyed by column name (an unmeasured value is null). */
std::string telemetryJson(const FrameTelemetry& telemetry);

} // namespace ff::runtime
