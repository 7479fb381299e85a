#pragma once

// One streaming session: everything between a scene file and a drawn frame, and the only frame
// loop farfield has. `render`, `view`, `replay` and the benchmarks all draw through it.
//
//   scene file ─► IPageSource ─► PageCache ─► CachedPageAccess ┐   (or MappedPageAccess:
//                 (cache/)       (cache/, I/O threads,         │    every page mapped, frames
//                                 hard budget)                 │    always complete)
//                                                              ▼
//   frame(FrameContext):  pump ─► traverse ─► draw batches ─► finish ─► prefetch ─► telemetry
//                         (install   (ITraversal,  (Renderer:       (image or   (the camera
//                          finished   never waits)  IDrawSink,       window)     ahead, a
//                          reads)                   IUploadGate)                 quarter priority)
//
// Layers of page access, bottom up: IPageSource is where page bytes come from (a file today;
// HTTP ranges or object storage next: open(source) takes any), PageCache keeps a budgeted
// resident set of them filled by background reads, IPageAccess is what one frame sees of pages
// (Ready, Pending or Failed, never a wait). The scene index (header and tables) is read through
// the source too, once, at open. The session owns all of them, so nothing outside runtime/
// names the cache.

#include <ff/runtime/Camera.h>
#include <ff/runtime/FrameContext.h>
#include <ff/runtime/FrameStats.h>
#include <ff/runtime/FrameTelemetry.h>
#include <ff/runtime/Image.h>
#include <ff/runtime/Renderer.h>
#include <ff/storage/PageSource.h>
#include <ff/storage/SceneIndex.h>
#include <ff/storage/Status.h>

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <vector>

namespace ff::runtime {

struct SessionOptions {
    /** Hard budget for resident page bytes (format 2: as decoded). 0: no cache, every page
     *  through the scene file's memory map (synchronous: every frame is complete); a format 2
     *  file, whose geometry must be decoded, streams through a cache of every page decoded (at
     *  most half the machine's memory) and every frame waits for the pages it lacks. */
    std::uint64_t cacheBytes = 0;
    /** Background read threads (streaming). */
    unsigned ioThreads = 2;
    /** Reads queued or under way at once at most (streaming); below the cache's default (64)
     *  means the default. */
    std::uint32_t maxInFlight = 0;
    RendererOptions renderer;
};

/** A rendered frame with its statistics. */
struct Frame {
    Image image;
    FrameStats stats;
};

/** What the session did since it opened (the page cache's counters; 0 when mapped). */
struct SessionTotals {
    std::uint64_t frames = 0;
    std::uint64_t requests = 0;
    std::uint64_t cancelled = 0;
    std::uint64_t refused = 0;
    std::uint64_t noRoom = 0;
    std::uint64_t evicted = 0;
    std::uint64_t dropped = 0;
    std::uint64_t bytesRead = 0;
    /** Distinct pages read at least once, in bytes: what the frames needed. */
    std::uint64_t uniqueBytes = 0;
    std::uint64_t peakResidentBytes = 0; ///< the most resident page bytes at a frame's end
    std::uint64_t budgetBytes = 0;
    /** Fetch to resident (cache::PageCacheStats::fetchToResident), seconds: median and p95 of
     *  the pages installed (0 without a cache or before the first install). */
    double fetchToResidentP50 = 0.0;
    double fetchToResidentP95 = 0.0;
};

/**
 * See the architecture note above. Needs a current GL 4.5 context from open() on (an
 * OffscreenContext or a window). Main thread only.
 */
class StreamingSession {
public:
    /**
     * Opens `scenePath`; with a cache, makes the minimum working set resident (the root node's
     * page, without which no frame can draw anything) before returning. Errors: the scene
     * file's, OutOfBudget when the budget cannot hold the root page (the message names
     * --cache-mb), and the renderer's.
     */
    [[nodiscard]] static Result<std::unique_ptr<StreamingSession>>
    open(const std::filesystem::path& scenePath, const SessionOptions& options = {});
    /**
     * Streams the scene `source` serves (a file, a range server, ...): the scene index is read
     * through it (storage::SceneIndex::read), then every page through the budgeted cache, the
     * root's page resident before returning. Needs options.cacheBytes > 0 (OutOfBudget below
     * one page); errors as above.
     */
    [[nodiscard]] static Result<std::unique_ptr<StreamingSession>>
    open(std::shared_ptr<storage::IPageSource> source, const SessionOptions& options);
    ~StreamingSession();
    StreamingSession(const StreamingSession&) = delete;
    StreamingSession& operator=(const StreamingSession&) = delete;

    /** The scene's header and tables (a SceneFile when mapped; read through the source when
     *  streaming). */
    const storage::SceneIndex& scene() const noexcept;
    /** Pages come through a budgeted cache (else every page is mapped). */
    bool streams() const noexcept;

    /** One frame into an image: pump, traverse, draw, prefetch; lastFrame() has its telemetry. */
    [[nodiscard]] Result<Frame> render(const FrameContext& frame);
    /** As render(), but the frame waits for every page it lacks until nothing more fits the
     *  budget (a deterministic reference: `replay --sync`; every wait marks it stalled). */
    [[nodiscard]] Result<Frame> renderComplete(const FrameContext& frame);
    /** One frame into the default framebuffer (a window's back buffer), no readback. */
    [[nodiscard]] Result<FrameStats> present(const FrameContext& frame);
    /**
     * The occlusion oracle (benchmarks): the frustum-culled frame drawn once, untimed, to learn
     * which triangles and cubes show at least one sample (Renderer::visibleParts), then drawn
     * again with exactly those. The frame returned, its stats and telemetry are the second
     * drawing's: what exact occlusion culling would cost, with the knowledge for free.
     * Needs every page mapped (a session without a cache). Errors: InvalidArgument with a cache.
     */
    [[nodiscard]] Result<Frame> renderOracle(const FrameContext& frame);

    /**
     * Prefetch along the camera's motion: after each following frame, the traversal also runs
     * for `camera` (where the camera will be a few frames on) only to ask for its pages, at a
     * quarter of the frame's priority. nullopt stops it. Does nothing without a cache.
     */
    void setPrefetchCamera(std::optional<Camera> camera);
    /** Changes the cache's budget (at least one page); no-op without a cache. */
    void setCacheBudget(std::uint64_t bytes);
    /** Replaces the renderer with one of `bytes` of GPU page arena (the old arena is freed
     *  first). Errors: the renderer's. */
    [[nodiscard]] Status setGpuBudget(std::uint64_t bytes);

    const FrameTelemetry& lastFrame() const noexcept;
    SessionTotals totals() const;
    /** Page failures first met by the last frame call (each reported once per session). */
    const std::vector<Status>& newFailures() const noexcept;

private:
    struct Impl;
    explicit StreamingSession(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> mImpl;
};

} // namespace ff::runtime
