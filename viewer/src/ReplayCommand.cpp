// `farfield replay`: the paging-behaviour test. Replays a camera path through the streaming
// page cache under a fixed budget and reports, per frame and in summary, what the cache did
// and what the viewer saw (frame time, debt, image error against everything resident).

#include "CameraOptions.h"
#include "Commands.h"
#include "ImageOutput.h"
#include "OutputFile.h"
#include "Percentile.h"
#include "StreamingPages.h"
#include "Units.h"

#include <ff/cache/PageCache.h>
#include <ff/cache/ScenePageSource.h>
#include <ff/runtime/CachedPageAccess.h>
#include <ff/runtime/CameraPath.h>
#include <ff/runtime/FrameRenderer.h>
#include <ff/runtime/ImageMetrics.h>
#include <ff/runtime/OffscreenContext.h>
#include <ff/runtime/PathCuts.h>
#include <ff/storage/ProcessMemory.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_set>
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
    float cubeAnisotropy = 1.0f;
    unsigned ioThreads = 2;
    std::size_t uploadsPerFrame = 64;
    int prefetchFrames = 4;
    std::string csv;
    std::string json;
    std::string summary;
    std::string framesDir;
    bool error = false;
    bool coverage = false;
};

/** Counts pages read, through the source, so the replay knows the unique bytes the path needed. */
class CountingSource final : public cache::IPageSource {
public:
    explicit CountingSource(std::shared_ptr<cache::IPageSource> inner) : mInner(std::move(inner)) {}
    std::uint32_t pageSize() const override { return mInner->pageSize(); }
    std::uint64_t pageCount() const override { return mInner->pageCount(); }
    Status readPage(std::uint64_t index, std::span<std::byte> out) override {
        {
            std::lock_guard<std::mutex> lock(mMutex); // I/O threads read concurrently
            mPages.insert(index);
        }
        return mInner->readPage(index, out);
    }
    std::uint64_t uniquePages() const {
        std::lock_guard<std::mutex> lock(mMutex);
        return mPages.size();
    }

private:
    std::shared_ptr<cache::IPageSource> mInner;
    mutable std::mutex mMutex;
    std::unordered_set<std::uint64_t> mPages;
};

int runReplay(const ReplayArgs& args) {
    auto size = parseImageSize(args.size);
    if (!size)
        return reportError("replay", size.status().withContext("--size"));
    auto gpuBudget = parseByteSize(args.gpuBudget);
    if (!gpuBudget)
        return reportError("replay", gpuBudget.status().withContext("--gpu-budget"));
    if (args.cacheMb == 0 || args.uploadsPerFrame == 0 || args.ioThreads == 0)
        return reportError("replay", Status(ErrorCode::InvalidArgument, "--cache-mb, --uploads-per-frame and --io-threads must be positive"));

    auto path = readCameraPath(args.path);
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

    auto scene = storage::SceneFile::open(args.scene);
    if (!scene)
        return reportError("replay", scene.status().withContext(args.scene));
    auto source = cache::ScenePageSource::open(args.scene);
    if (!source)
        return reportError("replay", source.status().withContext(args.scene));
    auto counting = std::make_shared<CountingSource>(std::move(*source));
    // --sync is a reference: one reader and no refused requests make it repeatable. Asynchronous,
    // at least --uploads-per-frame reads may be under way, so that a frame can install that many.
    const auto maxInFlight = static_cast<std::uint32_t>(
            std::clamp<std::size_t>(args.uploadsPerFrame, cache::PageCacheOptions{}.maxInFlight, 1u << 20));
    auto streamingPages = args.sync ? openStreaming(**scene, counting, args.cacheMb << 20, 1, 1u << 30)
                                    : openStreaming(**scene, counting, args.cacheMb << 20, args.ioThreads, maxInFlight);
    if (!streamingPages)
        return reportError("replay", streamingPages.status());
    cache::PageCache* pageCache = streamingPages->cache.get();
    runtime::CachedPageAccess& access = *streamingPages->access;

    auto context = runtime::OffscreenContext::create();
    if (!context)
        return reportError("replay", context.status());
    runtime::RendererOptions rendererOptions;
    rendererOptions.gpuBudgetBytes = *gpuBudget;
    auto streaming = runtime::FrameRenderer::create(**scene, access, rendererOptions);
    if (!streaming)
        return reportError("replay", streaming.status());
    std::unique_ptr<runtime::FrameRenderer> complete; // everything resident: the error reference
    if (args.error) {
        auto reference = runtime::FrameRenderer::create(**scene, rendererOptions);
        if (!reference)
            return reportError("replay", reference.status());
        complete = std::move(*reference);
    }

    runtime::SelectionOptions selection;
    selection.epsilonPixels = args.epsilon;
    selection.maxCubeAnisotropy = args.cubeAnisotropy;
    const runtime::Bounds bounds = sceneBounds(**scene);
    const glm::dvec3 origin = sceneOrigin(**scene);
    const std::int64_t frames = path->frameCount();
    nlohmann::json perFrame = nlohmann::json::array();
    std::ofstream csv;
    if (*csvFile) {
        csv.open((*csvFile)->temporaryPath(), std::ios::binary | std::ios::trunc);
        csv << "frame,time_s,frame_ms,select_ms,draw_ms,requests,hits,misses,bytes_read,resident_bytes,"
               "gpu_resident_bytes,in_flight,evicted,dropped,nodes_deferred,triangles,cubes,stalled,psnr_db,holes,"
               "node_page_bytes,geometry_page_bytes\n";
    }
    std::vector<double> frameMs;
    std::uint64_t debtFrames = 0;
    std::uint64_t stalledFrames = 0;
    std::uint64_t peakResident = 0;
    // The frame that used the most page bytes: its pages by type, and how much of them it used.
    struct FrameUse {
        runtime::FramePageUse pages;
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
    // Zero, not the stats after opening: frame 0 carries the root pages read before it, so the
    // per-frame columns add up to the summary's totals.
    cache::PageCacheStats previous{};

    for (std::int64_t f = 0; f < frames; ++f) {
        runtime::Camera camera = path->sample(path->frameTime(f), origin);
        camera.fitClipPlanes(bounds);
        if (cuts[static_cast<std::size_t>(f)]) {
            neverConverged += converged ? 0 : 1;
            ++segments;
            sinceCut = 0;
            converged = false;
        }

        if (args.prefetchFrames > 0 && !args.sync) {
            runtime::Camera ahead = path->sample(path->frameTime(std::min<std::int64_t>(f + args.prefetchFrames, frames - 1)), origin);
            ahead.fitClipPlanes(bounds);
            (*streaming)->setPrefetchCamera(ahead);
        }
        const auto start = std::chrono::steady_clock::now();
        pageCache->pump(args.uploadsPerFrame);
        Result<runtime::Frame> frame = (*streaming)->render(camera, selection, size->x, size->y);
        bool stalled = false;
        // --sync: the frame waits for what it lacks (a reference mode; every wait is a stall).
        while (args.sync && frame && frame->stats.nodesDeferred > 0) {
            const std::uint64_t before = pageCache->stats().completed;
            pageCache->drain();
            stalled = true;
            frame = (*streaming)->render(camera, selection, size->x, size->y);
            if (pageCache->stats().completed == before)
                break; // nothing more fits the budget: this frame is as good as it gets
        }
        if (!frame)
            return reportError("replay", frame.status());
        const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
        const auto& fresh = (*streaming)->newFailures();
        failures.insert(failures.end(), fresh.begin(), fresh.end());

        const cache::PageCacheStats& now = pageCache->stats();
        peakResident = std::max(peakResident, now.residentBytes);
        const runtime::FramePageUse& used = access.framePageUse();
        if (used.nodePages + used.geometryPages >= peakUse.pages.nodePages + peakUse.pages.geometryPages)
            peakUse = {used, frame->stats.nodesVisited, frame->stats.trianglesDrawn};
        const storage::ProcessMemory memory = storage::readProcessMemory();
        peakMemory.anonBytes = std::max(peakMemory.anonBytes, memory.anonBytes);
        peakMemory.fileBytes = std::max(peakMemory.fileBytes, memory.fileBytes);
        frameMs.push_back(ms);
        const bool debt = frame->stats.nodesDeferred > 0;
        debtFrames += debt ? 1 : 0;
        stalledFrames += stalled ? 1 : 0;
        if (!converged) {
            ++sinceCut;
            if (!debt) {
                converged = true;
                maxFramesToFullQuality = std::max(maxFramesToFullQuality, sinceCut);
            }
        }

        double psnr = NAN;
        std::uint64_t holes = 0;
        if (complete) {
            Result<runtime::Frame> reference = complete->render(camera, selection, size->x, size->y);
            if (!reference)
                return reportError("replay", reference.status());
            if (auto e = runtime::colorError(frame->image, reference->image))
                psnr = e->psnrSrgb;
            if (auto c = runtime::coverageError(frame->image, reference->image))
                holes = c->holes;
        }
        if (!args.framesDir.empty()) {
            char name[32];
            std::snprintf(name, sizeof(name), "frame-%05lld.png", static_cast<long long>(f));
            if (Status written = writeImage(std::filesystem::path(args.framesDir) / name, frame->image, args.coverage); !written)
                return reportError("replay", written);
        }

        const nlohmann::json row = {
                {"frame", f},
                {"time_s", path->frameTime(f)},
                {"frame_ms", ms},
                {"select_ms", frame->stats.selectMs},
                {"draw_ms", frame->stats.drawMs},
                {"requests", now.requests - previous.requests},
                {"hits", now.hits - previous.hits},
                {"misses", now.misses - previous.misses},
                {"bytes_read", now.bytesRead - previous.bytesRead},
                {"resident_bytes", now.residentBytes},
                {"gpu_resident_bytes", (*streaming)->gpuResidentBytes()},
                {"in_flight", now.inFlight},
                {"evicted", now.evicted - previous.evicted},
                {"dropped", now.dropped - previous.dropped},
                {"nodes_deferred", frame->stats.nodesDeferred},
                {"triangles", frame->stats.trianglesDrawn},
                {"cubes", frame->stats.cubesDrawn},
                {"stalled", stalled},
                {"psnr_db", std::isfinite(psnr) ? nlohmann::json(psnr) : nlohmann::json(nullptr)},
                {"holes", holes},
                {"node_page_bytes", used.nodePages * (*scene)->pageSize()},
                {"geometry_page_bytes", used.geometryPages * (*scene)->pageSize()},
        };
        if (csv.is_open()) {
            csv << f << ',' << row["time_s"] << ',' << ms << ',' << frame->stats.selectMs << ',' << frame->stats.drawMs
                << ',' << row["requests"] << ',' << row["hits"] << ',' << row["misses"] << ',' << row["bytes_read"] << ','
                << now.residentBytes << ',' << row["gpu_resident_bytes"] << ',' << now.inFlight << ','
                << row["evicted"] << ',' << row["dropped"] << ',' << frame->stats.nodesDeferred << ','
                << frame->stats.trianglesDrawn << ',' << frame->stats.cubesDrawn << ',' << (stalled ? 1 : 0) << ','
                << (std::isfinite(psnr) ? std::to_string(psnr) : std::string()) << ',' << holes << ','
                << row["node_page_bytes"] << ',' << row["geometry_page_bytes"] << '\n';
        }
        perFrame.push_back(row);
        previous = now;
    }
    neverConverged += converged ? 0 : 1;

    const cache::PageCacheStats& total = pageCache->stats();
    const std::uint64_t uniqueBytes = counting->uniquePages() * (*scene)->pageSize();
    const std::uint32_t pageSize = (*scene)->pageSize();
    const auto share = [](std::uint64_t used, std::uint64_t slots) {
        return slots ? static_cast<double>(used) / static_cast<double>(slots) : 0.0;
    };
    const nlohmann::json summary = {
            {"scene", args.scene},
            {"path", args.path},
            {"mode", args.sync ? "sync" : "async"},
            {"frames", frames},
            {"p50_ms", percentile(frameMs, 0.50)},
            {"p95_ms", percentile(frameMs, 0.95)},
            {"p99_ms", percentile(frameMs, 0.99)},
            {"bytes_read", total.bytesRead},
            {"unique_bytes", uniqueBytes},
            {"over_fetch", uniqueBytes ? static_cast<double>(total.bytesRead) / static_cast<double>(uniqueBytes) : 0.0},
            {"peak_resident_bytes", peakResident},
            // The frame that used the most pages: node against geometry page bytes, and the
            // share of their slots it used (records visited, triangles drawn).
            {"frame_node_bytes", peakUse.pages.nodePages * pageSize},
            {"frame_geometry_bytes", peakUse.pages.geometryPages * pageSize},
            {"frame_nodes_visited", peakUse.nodesVisited},
            {"frame_triangles_drawn", peakUse.trianglesDrawn},
            {"frame_node_slot_use", share(peakUse.nodesVisited, peakUse.pages.nodePages * storage::nodesPerPage(pageSize))},
            {"frame_triangle_slot_use",
             share(peakUse.trianglesDrawn, peakUse.pages.geometryPages * storage::trianglesPerPage(pageSize))},
            {"budget_bytes", pageCache->budgetBytes()},
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
        if (const Status written = (*jsonFile)->commitText(perFrame.dump(1) + "\n"); !written)
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
    cmd->add_option("--gpu-budget", args->gpuBudget, "GPU memory for geometry pages")->capture_default_str();
    cmd->add_flag("--sync", args->sync, "Wait for every page a frame wants (deterministic reference; counts stalls)");
    cmd->add_option("--size", args->size, "Image size WIDTHxHEIGHT")->capture_default_str();
    cmd->add_option("--epsilon", args->epsilon, "A cell whose box covers less than epsilon^2 pixels on screen is drawn as its color cube")->capture_default_str();
    cmd->add_option("--cube-anisotropy", args->cubeAnisotropy,
                    "Refuse colour cubes whose coverage differs more than this between axes (0..1; 1 = never)")
            ->check(CLI::Range(0.0f, 1.0f))
            ->capture_default_str();
    cmd->add_option("--io-threads", args->ioThreads, "Background read threads")->capture_default_str();
    cmd->add_option("--uploads-per-frame", args->uploadsPerFrame, "Finished reads installed per frame at most (also the reads under way at most, if above 64)")
            ->capture_default_str();
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
