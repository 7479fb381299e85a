// `farfield replay`: the paging-behaviour test. Replays a camera path through the streaming
// page cache under a fixed budget and reports, per frame and in summary, what the cache did
// and what the viewer saw (frame time, debt, image error against everything resident).

#include "CameraFlags.h"
#include "Commands.h"
#include "FrameFlags.h"
#include "ImageOutput.h"
#include "OutputFile.h"

#include <ff/runtime/CameraPath.h>
#include <ff/runtime/FrameTelemetry.h>
#include <ff/runtime/ImageMetrics.h>
#include <ff/runtime/OffscreenContext.h>
#include <ff/runtime/PathCuts.h>
#include <ff/runtime/Percentile.h>
#include <ff/runtime/StreamingSession.h>
#include <ff/runtime/Units.h>
#include <ff/storage/ProcessMemory.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

namespace ff::viewer {

namespace {

struct ReplayArgs {
    std::string scene;
    std::string path;
    std::uint64_t cacheMb = 512;
    std::string gpuBudget = "512MiB";
    bool sync = false;
    std::string size = "640x480";
    float epsilon = 1.0f;
    runtime::Representation representation = runtime::Representation::Auto;
    runtime::SplatStyle splats;
    float cubeAnisotropy = 1.0f;
    unsigned ioThreads = 2;
    std::size_t uploadsPerFrame = 64;
    std::uint32_t gpuUploadsPerFrame = 0;
    int prefetchFrames = 4;
    runtime::OcclusionOptions occlusion;
    std::string csv;
    std::string json;
    std::string summary;
    std::string framesDir;
    bool error = false;
    bool coverage = false;
};

std::string joinCsv(const std::vector<std::string>& cells) {
    std::string line;
    for (std::size_t i = 0; i < cells.size(); ++i)
        line += (i ? "," : "") + cells[i];
    return line;
}

int runReplay(const ReplayArgs& args) {
    auto size = runtime::parseImageSize(args.size);
    if (!size)
        return reportError("replay", size.status().withContext("--size"));
    auto gpuBudget = runtime::parseByteSize(args.gpuBudget);
    if (!gpuBudget)
        return reportError("replay", gpuBudget.status().withContext("--gpu-budget"));
    if (args.cacheMb == 0 || args.uploadsPerFrame == 0 || args.ioThreads == 0)
        return reportError("replay", Status(ErrorCode::InvalidArgument, "--cache-mb, --uploads-per-frame and --io-threads must be positive"));

    auto path = runtime::readCameraPath(args.path);
    if (!path)
        return reportError("replay", path.status());
    // Outputs first: an unwritable path fails before the replay, not after it.
    auto csvFile = reserveIfNamed(args.csv, OutputKind::Text);
    if (!csvFile)
        return reportError("replay", csvFile.status().withContext("--csv"));
    auto jsonFile = reserveIfNamed(args.json, OutputKind::Text);
    if (!jsonFile)
        return reportError("replay", jsonFile.status().withContext("--json"));
    auto summaryFile = reserveIfNamed(args.summary, OutputKind::Text);
    if (!summaryFile)
        return reportError("replay", summaryFile.status().withContext("--summary"));
    if (!args.framesDir.empty()) {
        if (const Status folder = prepareOutputFolder(args.framesDir); !folder)
            return reportError("replay", folder.withContext("--frames-dir"));
    }

    auto context = runtime::OffscreenContext::create();
    if (!context)
        return reportError("replay", context.status());
    // --sync is a reference: one reader and no refused requests make it repeatable. Asynchronous,
    // at least --uploads-per-frame reads may be under way, so that a frame can install that many.
    runtime::SessionOptions sessionOptions;
    sessionOptions.cacheBytes = args.cacheMb << 20;
    sessionOptions.ioThreads = args.sync ? 1 : args.ioThreads;
    sessionOptions.maxInFlight =
            args.sync ? 1u << 30 : static_cast<std::uint32_t>(std::min<std::size_t>(args.uploadsPerFrame, 1u << 20));
    sessionOptions.renderer.gpuBudgetBytes = *gpuBudget;
    auto session = runtime::StreamingSession::open(args.scene, sessionOptions);
    if (!session)
        return reportError("replay", session.status().withContext(args.scene));
    runtime::StreamingSession& streaming = **session;
    const storage::SceneIndex& scene = streaming.scene();
    std::unique_ptr<runtime::StreamingSession> complete; // everything resident: the error reference
    if (args.error) {
        runtime::SessionOptions mapped;
        mapped.renderer = sessionOptions.renderer;
        auto reference = runtime::StreamingSession::open(args.scene, mapped);
        if (!reference)
            return reportError("replay", reference.status().withContext(args.scene));
        complete = std::move(*reference);
    }

    runtime::FrameContext frameContext;
    frameContext.width = size->x;
    frameContext.height = size->y;
    frameContext.selection.epsilonPixels = args.epsilon;
    frameContext.selection.representation = args.representation;
    frameContext.selection.splats = args.splats;
    frameContext.selection.maxCubeAnisotropy = args.cubeAnisotropy;
    frameContext.occlusion = args.occlusion;
    frameContext.budgets.pageInstallsPerFrame = args.uploadsPerFrame;
    frameContext.budgets.gpuUploadsPerFrame = args.sync ? 0 : args.gpuUploadsPerFrame;
    const runtime::Bounds bounds = runtime::sceneBounds(scene);
    const glm::dvec3 origin = runtime::sceneOrigin(scene);
    const std::int64_t frames = path->frameCount();
    std::string perFrameJson = "[";
    std::ofstream csv;
    if (*csvFile) {
        csv.open((*csvFile)->temporaryPath(), std::ios::binary | std::ios::trunc);
        csv << joinCsv(runtime::telemetryColumnNames()) << '\n';
    }
    std::vector<double> frameMs;
    std::uint64_t debtFrames = 0;
    std::uint64_t stalledFrames = 0;
    // The frame that used the most page bytes: its pages by type, and how much of them it used.
    struct FrameUse {
        std::uint64_t nodePageBytes = 0;
        std::uint64_t geometryPageBytes = 0;
        std::uint64_t nodesVisited = 0;
        std::uint64_t trianglesDrawn = 0;
    } peakUse;
    storage::ProcessMemory peakMemory; // resident memory split: heap and stacks apart from mapped files
    std::vector<Status> failures;
    // Frames to full quality, per segment of the path: from a cut (a teleport, or the cold start;
    // runtime/PathCuts.h) to the first frame without debt. A segment whose every frame has debt
    // never converged, and says so.
    const std::vector<bool> cuts = runtime::findPathCuts(*path, bounds.radius(), origin);
    std::int64_t sinceCut = 0;
    std::int64_t maxFramesToFullQuality = 0;
    std::uint64_t segments = 0;
    std::uint64_t neverConverged = 0;
    bool converged = true; // no segment is open before frame 0

    for (std::int64_t f = 0; f < frames; ++f) {
        frameContext.camera = path->sample(path->frameTime(f), origin);
        frameContext.camera.fitClipPlanes(bounds);
        frameContext.timeSeconds = path->frameTime(f);
        if (cuts[static_cast<std::size_t>(f)]) {
            neverConverged += converged ? 0 : 1;
            ++segments;
            sinceCut = 0;
            converged = false;
        }

        if (args.prefetchFrames > 0 && !args.sync) {
            runtime::Camera ahead = path->sample(path->frameTime(std::min<std::int64_t>(f + args.prefetchFrames, frames - 1)), origin);
            ahead.fitClipPlanes(bounds);
            streaming.setPrefetchCamera(ahead);
        }
        // --sync: the frame waits for what it lacks (a reference mode; every wait is a stall).
        Result<runtime::Frame> frame = args.sync ? streaming.renderComplete(frameContext) : streaming.render(frameContext);
        if (!frame)
            return reportError("replay", frame.status());
        const auto& fresh = streaming.newFailures();
        failures.insert(failures.end(), fresh.begin(), fresh.end());
        runtime::FrameTelemetry telemetry = streaming.lastFrame();

        if (telemetry.nodePageBytes + telemetry.geometryPageBytes >= peakUse.nodePageBytes + peakUse.geometryPageBytes)
            peakUse = {telemetry.nodePageBytes, telemetry.geometryPageBytes, frame->stats.nodesVisited,
                       frame->stats.trianglesDrawn};
        const storage::ProcessMemory memory = storage::readProcessMemory();
        peakMemory.anonBytes = std::max(peakMemory.anonBytes, memory.anonBytes);
        peakMemory.fileBytes = std::max(peakMemory.fileBytes, memory.fileBytes);
        frameMs.push_back(telemetry.frameMs);
        const bool debt = frame->stats.nodesDeferred > 0;
        debtFrames += debt ? 1 : 0;
        stalledFrames += telemetry.stalled ? 1 : 0;
        if (!converged) {
            ++sinceCut;
            if (!debt) {
                converged = true;
                maxFramesToFullQuality = std::max(maxFramesToFullQuality, sinceCut);
            }
        }

        if (complete) {
            Result<runtime::Frame> reference = complete->render(frameContext);
            if (!reference)
                return reportError("replay", reference.status());
            if (auto e = runtime::colorError(frame->image, reference->image))
                telemetry.psnrDb = e->psnrSrgb;
            if (auto c = runtime::coverageError(frame->image, reference->image))
                telemetry.holes = c->holes;
        }
        if (!args.framesDir.empty()) {
            char name[32];
            std::snprintf(name, sizeof(name), "frame-%05lld.png", static_cast<long long>(f));
            if (Status written = writeImage(std::filesystem::path(args.framesDir) / name, frame->image, args.coverage); !written)
                return reportError("replay", written);
        }
        if (csv.is_open())
            csv << joinCsv(runtime::telemetryCsvCells(telemetry)) << '\n';
        perFrameJson += (f > 0 ? ",\n" : "\n") + runtime::telemetryJson(telemetry);
    }
    neverConverged += converged ? 0 : 1;

    const runtime::SessionTotals total = streaming.totals();
    const std::uint64_t uniqueBytes = total.uniqueBytes;
    const std::uint32_t pageSize = scene.pageSize();
    const bool formatTwo = scene.formatVersion() == storage::kFormatVersion2;
    const auto share = [](std::uint64_t used, std::uint64_t slots) {
        return slots ? static_cast<double>(used) / static_cast<double>(slots) : 0.0;
    };
    const nlohmann::json summary = {
            {"scene", args.scene},
            {"path", args.path},
            {"mode", args.sync ? "sync" : "async"},
            {"frames", frames},
            {"p50_ms", runtime::percentile(frameMs, 0.50)},
            {"p95_ms", runtime::percentile(frameMs, 0.95)},
            {"p99_ms", runtime::percentile(frameMs, 0.99)},
            {"bytes_read", total.bytesRead},
            {"unique_bytes", uniqueBytes},
            {"over_fetch", uniqueBytes ? static_cast<double>(total.bytesRead) / static_cast<double>(uniqueBytes) : 0.0},
            {"peak_resident_bytes", total.peakResidentBytes},
            // From a page's request to its install in the cache, upper edges of the histogram's
            // buckets (within 9 %, cache/LatencyHistogram.h).
            {"fetch_to_resident_p50_ms", total.fetchToResidentP50 * 1e3},
            {"fetch_to_resident_p95_ms", total.fetchToResidentP95 * 1e3},
            // The frame that used the most pages: node against geometry page bytes, and the
            // share of their slots it used (records visited, triangles drawn).
            {"frame_node_bytes", peakUse.nodePageBytes},
            {"frame_geometry_bytes", peakUse.geometryPageBytes},
            {"frame_nodes_visited", peakUse.nodesVisited},
            {"frame_triangles_drawn", peakUse.trianglesDrawn},
            {"frame_node_slot_use",
             share(peakUse.nodesVisited,
                   peakUse.nodePageBytes / pageSize *
                           (formatTwo ? storage::nodesPerPageV2(pageSize) : storage::nodesPerPage(pageSize)))},
            // Format 2's pages hold clusters of any size, not triangle slots: null there, where
            // geometry bytes a drawn triangle (the pages' share the frame did not draw included)
            // says how well they are used.
            {"frame_triangle_slot_use",
             formatTwo ? nlohmann::json(nullptr)
                       : nlohmann::json(share(peakUse.trianglesDrawn,
                                              peakUse.geometryPageBytes / pageSize * storage::trianglesPerPage(pageSize)))},
            {"frame_geometry_bytes_per_triangle", share(peakUse.geometryPageBytes, peakUse.trianglesDrawn)},
            {"budget_bytes", total.budgetBytes},
            {"debt_frames", debtFrames},
            {"stalled_frames", stalledFrames},
            // null when a segment never reached full quality: its count is in never_converged.
            {"max_frames_to_full_quality",
             neverConverged > 0 ? nlohmann::json(nullptr) : nlohmann::json(maxFramesToFullQuality)},
            {"path_segments", segments},
            {"never_converged", neverConverged},
            {"requests", total.requests},
            {"cancelled", total.cancelled},
            {"refused", total.refused},
            {"no_room", total.noRoom},
            {"evicted", total.evicted},
            {"dropped", total.dropped},
            {"failed_pages", failures.size()},
            {"peak_rss_anon_bytes", peakMemory.anonBytes},
            {"peak_rss_file_bytes", peakMemory.fileBytes},
    };
    if (*csvFile) {
        csv.close();
        Status written = csv ? (*csvFile)->commit() : Status(ErrorCode::IoError, "cannot write " + args.csv);
        if (!written)
            return reportError("replay", written);
    }
    if (*jsonFile) {
        if (const Status written = (*jsonFile)->commitText(perFrameJson + "\n]\n"); !written)
            return reportError("replay", written);
    }
    if (*summaryFile) {
        if (const Status written = (*summaryFile)->commitText(summary.dump(2) + "\n"); !written)
            return reportError("replay", written);
    }
    std::printf("%s\n", summary.dump().c_str());
    for (const Status& failure : failures)
        reportError("replay", failure.withContext(args.scene));
    return failures.empty() ? 0 : 1;
}

} // namespace

CommandRunner addReplayCommand(CLI::App& app) {
    auto args = std::make_shared<ReplayArgs>();
    CLI::App* cmd = app.add_subcommand(
            "replay", "Replay a camera path through the streaming cache under a budget; per-frame paging telemetry");
    cmd->add_option("scene", args->scene, "Scene file (.ffs)")->required();
    cmd->add_option("path", args->path, "Camera path (.json, see `farfield path`)")->required();
    cmd->add_option("--cache-mb", args->cacheMb, "Hard budget for resident pages, MiB")->capture_default_str();
    addGpuBudgetOption(*cmd, args->gpuBudget);
    cmd->add_flag("--sync", args->sync, "Wait for every page a frame wants (deterministic reference; counts stalls)");
    cmd->add_option("--size", args->size, "Image size WIDTHxHEIGHT")->capture_default_str();
    addEpsilonOption(*cmd, args->epsilon);
    addRepresentationOption(*cmd, args->representation);
    addSplatOptions(*cmd, args->splats);
    addCubeAnisotropyOption(*cmd, args->cubeAnisotropy);
    addOcclusionOptions(*cmd, args->occlusion);
    cmd->add_option("--io-threads", args->ioThreads, "Background read threads")->capture_default_str();
    cmd->add_option("--uploads-per-frame", args->uploadsPerFrame, "Finished reads installed per frame at most (also the reads under way at most, if above 64)")
            ->capture_default_str();
    addGpuUploadsOption(*cmd, args->gpuUploadsPerFrame); // --sync: no bound
    cmd->add_option("--prefetch-frames", args->prefetchFrames,
                    "Also ask for the pages of the view this many frames ahead on the path (0: off)")
            ->capture_default_str();
    cmd->add_option("--csv", args->csv, "Per-frame telemetry as CSV");
    cmd->add_option("--json", args->json, "Per-frame telemetry as JSON");
    cmd->add_option("--summary", args->summary, "Summary JSON (frames, p50/p95/p99_ms, bytes_read, ...)");
    cmd->add_option("--frames-dir", args->framesDir, "Write every frame as PNG here");
    cmd->add_flag("--coverage-alpha", args->coverage, "Frames written with coverage as alpha");
    cmd->add_flag("--error", args->error, "Also render each frame with everything resident and report PSNR and holes");
    return [args]() { return runReplay(*args); };
}

} // namespace ff::viewer
