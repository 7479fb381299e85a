#include "CachedPageAccess.h"
#include "CachedClusterPage.h"
#include "GeometryDecodeStage.h"
#include "NodePages.h"

#include <ff/cache/PageCache.h>
#include <ff/cache/ScenePageSource.h>
#include <ff/runtime/BackToFrontTraversal.h>
#include <ff/runtime/OcclusionTraversal.h>
#include <ff/runtime/PageAccess.h>
#include <ff/runtime/StreamingSession.h>

#include <algorithm>
#include <chrono>
#include <mutex>
#include <string>
#include <unordered_set>

#include <unistd.h>

namespace ff::runtime {

namespace {

bool isV2(const storage::SceneIndex& scene) {
    return scene.formatVersion() == storage::kFormatVersion2;
}

/** Each prototype's position grid: what format 2's clusters are dequantized on. */
std::vector<storage::PositionGrid> positionGrids(const storage::SceneIndex& scene) {
    std::vector<storage::PositionGrid> grids;
    grids.reserve(scene.prototypesV2().size());
    for (const storage::PrototypeV2& p : scene.prototypesV2())
        grids.push_back(p.grid);
    return grids;
}

/** What a session without --cache-mb keeps of a format 2 file: every page as the cache keeps
 *  it, up to half the machine's memory (a file larger than that is drawn as well as that
 *  holds). */
std::uint64_t unbudgetedBytes(const storage::IPageSource& source) {
    const ClusterPageIndexer sizing({});
    const std::uint64_t everything =
            source.pageCount() * std::uint64_t{sizing.maxDecodedBytes(source.pageSize())};
    const long pages = sysconf(_SC_PHYS_PAGES);
    const long pageBytes = sysconf(_SC_PAGESIZE);
    if (pages <= 0 || pageBytes <= 0)
        return everything;
    return std::min(everything, static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(pageBytes) / 2);
}

double millisecondsSince(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
            .count();
}

/** Counts the distinct pages read through the source: the unique bytes a session needed. */
class CountingSource final : public storage::IPageSource {
public:
    explicit CountingSource(std::shared_ptr<storage::IPageSource> inner)
        : mInner(std::move(inner)) {}
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
    std::shared_ptr<storage::IPageSource> mInner;
    mutable std::mutex mMutex;
    std::unordered_set<std::uint64_t> mPages;
};

// Ends the page access's frame on every path out, so a failed frame still cancels the requests
// it no longer wants.
class FrameBracket {
public:
    explicit FrameBracket(IPageAccess& pages)
        : mPages(pages) {
        mPages.beginFrame();
    }
    ~FrameBracket() { mPages.endFrame(); }
    FrameBracket(const FrameBracket&) = delete;
    FrameBracket& operator=(const FrameBracket&) = delete;

private:
    IPageAccess& mPages;
};

// Brackets the passes of a frame drawn until it is complete: only the last pass's occlusion
// answers stay in the history (OcclusionTraversal.h), on every path out.
class RedrawableFrame {
public:
    explicit RedrawableFrame(OcclusionTraversal& traversal)
        : mTraversal(traversal) {
        mTraversal.beginRedrawableFrame();
    }
    ~RedrawableFrame() { mTraversal.endRedrawableFrame(); }
    RedrawableFrame(const RedrawableFrame&) = delete;
    RedrawableFrame& operator=(const RedrawableFrame&) = delete;

private:
    OcclusionTraversal& mTraversal;
};

} // namespace

struct StreamingSession::Impl {
    /** Mapped sessions: the file, which is the scene index too. */
    std::unique_ptr<storage::SceneFile> file;
    /** Streaming sessions: the index, read through the page source. */
    std::optional<storage::SceneIndex> streamedIndex;
    /** The scene's index: the mapped file's, or the one read through the source. */
    const storage::SceneIndex& scene() const { return file ? *file : *streamedIndex; }
    std::shared_ptr<CountingSource> counting;
    std::unique_ptr<cache::PageCache> cache;
    /** Format 2: decodes the pages the renderer is about to upload (the cache keeps them
     *  encoded). After the cache, before the renderer: destroyed before the one, after the other. */
    std::unique_ptr<GeometryDecodeStage> decodeStage;
    DecodeStageStats previousDecode{}; ///< the stage's counters at the end of the last frame
    /** Every frame waits for the pages it lacks (a format 2 file opened without a budget: its
     *  geometry is decoded by the cache, so it cannot be mapped). */
    bool completeFrames = false;
    std::unique_ptr<IPageAccess> pages;
    CachedPageAccess* cachedPages = nullptr; ///< pages, when streaming
    std::unique_ptr<BackToFrontTraversal> traversal;
    std::unique_ptr<OcclusionTraversal> occlusionTraversal;
    std::unique_ptr<BackToFrontTraversal> prefetchTraversal; ///< its own failures and scratch
    std::unique_ptr<Renderer> renderer;
    RendererOptions rendererOptions;
    NoVisibility visibility;
    std::optional<Camera> prefetchCamera;
    FrameTelemetry last;
    cache::PageCacheStats previous{}; ///< the cache's counters at the end of the last frame
    std::int64_t frames = 0;
    std::uint64_t peakResidentBytes = 0;
    std::vector<Status> failures; ///< first met during the last frame call
    /** Where the frame's batches go instead of the renderer (the oracle's filter). */
    IDrawSink* sinkOverride = nullptr;

    /** The traversals and the renderer, once `scene` and `pages` are set. */
    Status startDrawing(const SessionOptions& options);
    /** pump → traverse → draw → finish → prefetch, inside one page-access frame. */
    template <typename Finish>
    Status
    frame(const FrameContext& context,
          FrameOutput output,
          FrameStats& stats,
          double& prefetchMs,
          Finish&& finish);
    /** One frame into `result` (its stats start afresh). */
    Status frameToImage(const FrameContext& context, Frame& result, double& prefetchMs);
    /** Draws the frame with `draw` again, after waiting for every read it asked for, until it
     *  lacks no page that fits the budget (`stats`: what `draw` counts into). */
    template <typename Draw> Status untilComplete(const FrameStats& stats, bool& stalled, Draw&& draw);
    /** frameToImage() until the frame lacks no page that fits the budget. */
    Status completeFrameToImage(
            const FrameContext& context, Frame& result, double& prefetchMs, bool& stalled);
    /** A public frame call: pump, then `body` (one frame or, waiting, several), then the
     *  telemetry of what `stats` ends as. */
    template <typename Body>
    Status call(const FrameContext& context, FrameStats& stats, Body&& body);
    void prefetch(const FrameContext& context, double& prefetchMs);
    void pump(std::size_t installs, double& pumpMs);
    void
    record(const FrameContext& context,
           const FrameStats& stats,
           double frameMs,
           double pumpMs,
           double prefetchMs,
           bool stalled);
};

StreamingSession::StreamingSession(std::unique_ptr<Impl> impl)
    : mImpl(std::move(impl)) {}
StreamingSession::~StreamingSession() = default;

Result<std::unique_ptr<StreamingSession>>
StreamingSession::open(const std::filesystem::path& scenePath, const SessionOptions& options) {
    if (options.cacheBytes > 0) {
        FF_ASSIGN_OR_RETURN(
                std::unique_ptr<cache::ScenePageSource> source,
                cache::ScenePageSource::open(scenePath));
        return open(std::shared_ptr<storage::IPageSource>(std::move(source)), options);
    }
    auto impl = std::make_unique<Impl>();
    FF_ASSIGN_OR_RETURN(impl->file, storage::SceneFile::open(scenePath));
    if (isV2(*impl->file)) {
        impl.reset();
        FF_ASSIGN_OR_RETURN(
                std::unique_ptr<cache::ScenePageSource> source,
                cache::ScenePageSource::open(scenePath));
        SessionOptions unbudgeted = options;
        unbudgeted.cacheBytes = unbudgetedBytes(*source);
        FF_ASSIGN_OR_RETURN(
                std::unique_ptr<StreamingSession> session,
                open(std::shared_ptr<storage::IPageSource>(std::move(source)), unbudgeted));
        session->mImpl->completeFrames = true;
        return session;
    }
    impl->pages = std::make_unique<MappedPageAccess>(*impl->file);
    FF_RETURN_IF_ERROR(impl->startDrawing(options));
    return std::unique_ptr<StreamingSession>(new StreamingSession(std::move(impl)));
}

Result<std::unique_ptr<StreamingSession>>
StreamingSession::open(std::shared_ptr<storage::IPageSource> source, const SessionOptions& options) {
    FF_ASSERT(source != nullptr);
    // The most one page takes resident: as read, or as format 2's decoder keeps it (known
    // once the index is read). By value: the source moves into the cache below.
    std::uint64_t pageBytes = source->pageSize();
    const auto rootTooLarge = [&options, &pageBytes] {
        return Status(
                ErrorCode::OutOfBudget,
                "--cache-mb " + std::to_string(options.cacheBytes >> 20) +
                        " cannot hold the scene's root page as the cache keeps it (" +
                        std::to_string(pageBytes >> 10) + " KiB)");
    };
    if (options.cacheBytes < pageBytes)
        return rootTooLarge();
    auto impl = std::make_unique<Impl>();
    // The index before the cache: it is read once, at open, and stays outside the budget.
    FF_ASSIGN_OR_RETURN(impl->streamedIndex, storage::SceneIndex::read(*source));
    const storage::SceneIndex& scene = impl->scene();
    FF_ASSIGN_OR_RETURN(const storage::NodeRef root, detail::sceneRoot(scene));
    impl->counting = std::make_shared<CountingSource>(std::move(source));
    cache::PageCacheOptions cacheOptions;
    cacheOptions.budgetBytes = options.cacheBytes;
    cacheOptions.ioThreads = options.ioThreads;
    cacheOptions.maxInFlight = std::max(cacheOptions.maxInFlight, options.maxInFlight);
    // A frame that needs more than the budget keeps the cut it has instead of reading pages
    // it can only drop (docs/methods.md, "At the budget's edge").
    cacheOptions.readOnlyWhatFits = true;
    if (isV2(scene)) {
        cacheOptions.decoder = std::make_shared<ClusterPageIndexer>(positionGrids(scene));
        pageBytes = cacheOptions.decoder->maxDecodedBytes(scene.pageSize());
        if (options.cacheBytes < pageBytes)
            return rootTooLarge();
    }
    FF_ASSIGN_OR_RETURN(impl->cache, cache::PageCache::create(impl->counting, cacheOptions));
    const std::uint64_t rootPage = root.page;
    impl->cache->request(rootPage, 1e30f);
    impl->cache->drain();
    if (impl->cache->state(rootPage) == cache::PageState::Failed)
        return impl->cache->failure(rootPage).value_or(
                Status(ErrorCode::IoError, "the root page is unreadable"));
    if (impl->cache->state(rootPage) != cache::PageState::Resident)
        return rootTooLarge();
    auto cached = std::make_unique<CachedPageAccess>(*impl->cache);
    impl->cachedPages = cached.get();
    impl->pages = std::move(cached);
    FF_RETURN_IF_ERROR(impl->startDrawing(options));
    return std::unique_ptr<StreamingSession>(new StreamingSession(std::move(impl)));
}

Status StreamingSession::Impl::startDrawing(const SessionOptions& options) {
    traversal = std::make_unique<BackToFrontTraversal>(scene(), *pages);
    occlusionTraversal = std::make_unique<OcclusionTraversal>(scene(), *pages);
    prefetchTraversal = std::make_unique<BackToFrontTraversal>(scene(), *pages);
    rendererOptions = options.renderer;
    if (isV2(scene())) {
        FF_ASSERT(cache != nullptr); // format 2 always streams through the cache
        FF_ASSIGN_OR_RETURN(
                decodeStage,
                GeometryDecodeStage::create(
                        *cache, positionGrids(scene()), scene().pageSize(), DecodeStageOptions{}));
    }
    FF_ASSIGN_OR_RETURN(renderer, Renderer::create(scene(), options.renderer, decodeStage.get()));
    return Status::ok();
}

const storage::SceneIndex& StreamingSession::scene() const noexcept {
    return mImpl->scene();
}
bool StreamingSession::streams() const noexcept {
    return mImpl->cache != nullptr;
}

void StreamingSession::Impl::pump(std::size_t installs, double& pumpMs) {
    if (!cache)
        return;
    const auto start = std::chrono::steady_clock::now();
    cache->pump(installs);
    pumpMs += millisecondsSince(start);
}

void StreamingSession::Impl::prefetch(const FrameContext& context, double& prefetchMs) {
    if (!prefetchCamera || !cache)
        return;
    const auto start = std::chrono::steady_clock::now();
    FrameContext ahead = context;
    ahead.camera = *prefetchCamera;
    ahead.selection.priorityScale *= 0.25f;
    ahead.selection.observer = nullptr;
    DiscardingSink discard;
    AdmitAll admitAll;
    FrameStats ignored;
    // Its only effect is the page requests its lookups make; what it would draw is dropped.
    // With occlusion culling, what the last tests found hidden is not fetched ahead either.
    const IVisibility& known = context.occlusion.enabled
                                       ? occlusionTraversal->history()
                                       : static_cast<const IVisibility&>(visibility);
    (void)prefetchTraversal->traverse(ahead, {discard, known, admitAll}, ignored);
    prefetchMs += millisecondsSince(start);
}

template <typename Finish>
Status StreamingSession::Impl::frame(
        const FrameContext& context,
        FrameOutput output,
        FrameStats& stats,
        double& prefetchMs,
        Finish&& finish) {
    const FrameBracket bracket(*pages);
    if (decodeStage)
        decodeStage->beginFrame();
    FF_RETURN_IF_ERROR(renderer->beginFrame(context, output, stats));
    const double drawBefore = stats.drawMs;
    const auto start = std::chrono::steady_clock::now();
    const bool culls =
            context.occlusion.enabled && context.selection.method == Method::Hierarchical;
    ITraversal& walker = culls ? static_cast<ITraversal&>(*occlusionTraversal) : *traversal;
    IDrawSink& sink = sinkOverride ? *sinkOverride : static_cast<IDrawSink&>(*renderer);
    const Status walked =
            walker.traverse(context, {sink, visibility, *renderer, renderer.get()}, stats);
    const auto& fresh = walker.newFailures();
    failures.insert(failures.end(), fresh.begin(), fresh.end());
    if (decodeStage) {
        std::vector<Status> undecodable = decodeStage->takeFailures();
        failures.insert(failures.end(), undecodable.begin(), undecodable.end());
    }
    FF_RETURN_IF_ERROR(walked);
    // The batches the renderer drew during the walk are draw time, and the occlusion tests
    // their own, not selection.
    stats.selectMs = millisecondsSince(start) - (stats.drawMs - drawBefore) - stats.occlusionMs;
    FF_RETURN_IF_ERROR(finish());
    prefetch(context, prefetchMs);
    stats.totalMs = stats.selectMs + stats.occlusionMs + stats.drawMs;
    return Status::ok();
}

Status StreamingSession::Impl::frameToImage(
        const FrameContext& context, Frame& result, double& prefetchMs) {
    result.stats = {};
    return frame(context, FrameOutput::Image, result.stats, prefetchMs, [&]() -> Status {
        FF_ASSIGN_OR_RETURN(result.image, renderer->finishImage(result.stats));
        return Status::ok();
    });
}

template <typename Body>
Status StreamingSession::Impl::call(const FrameContext& context, FrameStats& stats, Body&& body) {
    failures.clear();
    const auto start = std::chrono::steady_clock::now();
    double pumpMs = 0.0;
    double prefetchMs = 0.0;
    bool stalled = false;
    pump(context.budgets.pageInstallsPerFrame, pumpMs);
    FF_RETURN_IF_ERROR(body(prefetchMs, stalled));
    record(context, stats, millisecondsSince(start), pumpMs, prefetchMs, stalled);
    return Status::ok();
}

void StreamingSession::Impl::record(
        const FrameContext& context,
        const FrameStats& stats,
        double frameMs,
        double pumpMs,
        double prefetchMs,
        bool stalled) {
    FrameTelemetry t;
    t.frame = frames++;
    t.timeSeconds = context.timeSeconds;
    t.frameMs = frameMs;
    t.pumpMs = pumpMs;
    t.prefetchMs = prefetchMs;
    t.stats = stats;
    t.stalled = stalled;
    if (const std::uint64_t total = scene().header().instancedTriangles; total > 0)
        t.renderRatePercent =
                100.0 * static_cast<double>(stats.trianglesDrawn) / static_cast<double>(total);
    t.gpuResidentBytes = renderer->residentBytes();
    if (cache) {
        const cache::PageCacheStats& now = cache->stats();
        t.requests = now.requests - previous.requests;
        t.hits = now.hits - previous.hits;
        t.misses = now.misses - previous.misses;
        t.bytesRead = now.bytesRead - previous.bytesRead;
        t.bytesReadTotal = now.bytesRead;
        t.residentBytes = now.residentBytes;
        peakResidentBytes = std::max(peakResidentBytes, now.residentBytes);
        t.inFlight = now.inFlight;
        t.evicted = now.evicted - previous.evicted;
        t.dropped = now.dropped - previous.dropped;
        t.cancelled = now.cancelled - previous.cancelled;
        t.refused = now.refused - previous.refused;
        t.noRoom = now.noRoom - previous.noRoom;
        const FramePageUse& used = cachedPages->framePageUse();
        t.nodePageBytes = used.nodePages * scene().pageSize();
        t.geometryPageBytes = used.geometryPages * scene().pageSize();
        previous = now;
    }
    if (decodeStage) {
        const DecodeStageStats& now = decodeStage->stats();
        t.pagesDecoded = now.decoded - previousDecode.decoded;
        t.decodeMs = 1000.0 * (now.decodeSeconds - previousDecode.decodeSeconds);
        t.decodedHeldBytes = now.heldBytes;
        previousDecode = now;
    }
    last = t;
}

template <typename Draw>
Status StreamingSession::Impl::untilComplete(const FrameStats& stats, bool& stalled, Draw&& draw) {
    // What the stage was given to do (queued, or refused for want of room): waiting for the
    // decode threads may draw more.
    const auto decodeWork = [&] {
        return decodeStage ? decodeStage->stats().requested + decodeStage->stats().refused : 0;
    };
    std::uint64_t work = decodeWork();
    const RedrawableFrame redrawable(*occlusionTraversal);
    FF_RETURN_IF_ERROR(draw());
    // A complete frame also lacks no page: --method full defers nothing, it leaves pages out
    // (format 2: also pages not decoded yet, which it refuses to upload).
    const auto lacking = [&] {
        return stats.nodesDeferred + (decodeStage ? stats.uploadsRefused : 0) +
               (completeFrames ? stats.pagesMissing : 0);
    };
    std::uint64_t leastLacking = lacking();
    int triesWithoutGain = 0;
    while (cache && lacking() > 0) {
        const bool awaitsDecodes = decodeWork() != work;
        const std::uint64_t readBefore = cache->stats().completed;
        // Decodes first: their pins release cache pages the reads may need room from.
        if (decodeStage)
            decodeStage->drain();
        cache->drain();
        stalled = true;
        work = decodeWork();
        occlusionTraversal->redrawLastFrame();
        FF_RETURN_IF_ERROR(draw());
        if (cache->stats().completed != readBefore) {
            leastLacking = lacking(); // a read can deepen the cut: start counting afresh
            triesWithoutGain = 0;
            continue;
        }
        // Nothing more fits the budget and nothing is being decoded: as good as this frame gets.
        if (!awaitsDecodes)
            break;
        if (lacking() < leastLacking) {
            leastLacking = lacking();
            triesWithoutGain = 0;
        } else if (++triesWithoutGain >= 2) {
            // Two tries of decoding drew nothing more: the frame's pages do not fit the GPU
            // arena, and each try evicts what the next needs decoded again. A frame that has
            // to be complete decodes the rest as it draws, on this thread, once.
            renderer->setDecodeOnDraw(true);
            occlusionTraversal->redrawLastFrame();
            const Status drawn = draw();
            renderer->setDecodeOnDraw(false);
            return drawn;
        }
    }
    return Status::ok();
}

Status StreamingSession::Impl::completeFrameToImage(
        const FrameContext& context, Frame& result, double& prefetchMs, bool& stalled) {
    return untilComplete(result.stats, stalled, [&] { return frameToImage(context, result, prefetchMs); });
}

Result<Frame> StreamingSession::render(const FrameContext& context) {
    Impl& s = *mImpl;
    if (s.completeFrames)
        return renderComplete(context);
    Frame result;
    FF_RETURN_IF_ERROR(s.call(context, result.stats, [&](double& prefetchMs, bool&) {
        return s.frameToImage(context, result, prefetchMs);
    }));
    return result;
}

namespace {

/** Draws through the renderer and keeps a copy of every batch (the oracle's first drawing). */
class KeepingSink final : public IDrawSink {
public:
    explicit KeepingSink(Renderer& renderer) : mRenderer(renderer) {}
    Status draw(const DrawList& batch, FrameStats& stats) override {
        batches.push_back(batch);
        return mRenderer.draw(batch, stats);
    }
    std::vector<DrawList> batches;

private:
    Renderer& mRenderer;
};

/** Draws each batch with only the triangles and cubes the oracle found visible. The walk is
 *  deterministic, so batch k is the first drawing's batch k; one that is not is drawn whole.
 *  What it leaves out is counted here and taken off the frame's stats by countInto(): a walk
 *  may hand its batches another stats object (the cubes of a spilled frame are counted once,
 *  by its geometry pass). */
class VisibleOnlySink final : public IDrawSink {
public:
    VisibleOnlySink(Renderer& renderer, const std::vector<BatchVisibility>& visible, bool clustered)
        : mRenderer(renderer), mVisible(visible), mClustered(clustered) {}
    Status draw(const DrawList& batch, FrameStats& stats) override {
        const std::size_t k = mNext++;
        std::uint64_t triangles = 0;
        for (const GeometryDraw& draw : batch.geometry)
            triangles += draw.triangles;
        if (k >= mVisible.size() || mVisible[k].triangles.size() != triangles ||
            mVisible[k].cubes.size() != batch.cubes.size())
            return mRenderer.draw(batch, stats);
        const BatchVisibility& shows = mVisible[k];
        mScratch.transforms = batch.transforms;
        mScratch.localEyes = batch.localEyes;
        mScratch.cubesAsPoints = batch.cubesAsPoints;
        mScratch.cubesOcclude = batch.cubesOcclude;
        mScratch.splats = batch.splats;
        // Each run cut to the stretches of its items (triangles, or clusters with a triangle
        // that shows) that show (the walk counted them all).
        mScratch.geometry.clear();
        std::uint64_t bit = 0;
        for (const GeometryDraw& draw : batch.geometry) {
            mItems.clear();
            if (!itemTriangles(draw, mItems))
                return mRenderer.draw(batch, stats);
            std::uint32_t item = 0;
            std::uint64_t itemBit = bit;
            const auto shown = [&](std::uint32_t i, std::uint64_t from) {
                if (mItems[i] == 0)
                    return true; // a point cluster (splats): no triangle bits to judge it by
                for (std::uint32_t t = 0; t < mItems[i]; ++t)
                    if (shows.triangles[from + t])
                        return true;
                return false;
            };
            while (item < draw.count) {
                for (; item < draw.count && !shown(item, itemBit); itemBit += mItems[item++])
                    mTrianglesLeft += mItems[item];
                const std::uint32_t first = item;
                std::uint32_t kept = 0;
                for (; item < draw.count && shown(item, itemBit); itemBit += mItems[item++])
                    kept += mItems[item];
                if (item > first)
                    mScratch.geometry.push_back(
                            {draw.page,
                             draw.payload,
                             draw.first + first,
                             item - first,
                             draw.transform,
                             kept,
                             draw.payloadBytes,
                             draw.pointPixels});
            }
            bit += draw.triangles;
        }
        mDrawsLeft += static_cast<std::int64_t>(batch.geometry.size()) - static_cast<std::int64_t>(mScratch.geometry.size());
        mScratch.cubes.clear();
        for (std::size_t c = 0; c < batch.cubes.size(); ++c) {
            if (shows.cubes[c]) {
                mScratch.cubes.push_back(batch.cubes[c]);
                continue;
            }
            ++mCubesLeft;
            const CubeDraw& cube = batch.cubes[c];
            mFacesLeft += detail::cubeFacesToward(cube.boxMin, cube.boxMax, cube.faces, batch.localEyes[cube.transform], 1);
        }
        return mRenderer.draw(mScratch, stats);
    }

    /** Takes what was left out off the walk's counts; the triangles left out are the frame's
     *  occluded ones (of the cut the walk chose, not of the subtrees at full detail). */
    void countInto(FrameStats& stats) const {
        stats.trianglesDrawn -= mTrianglesLeft;
        stats.trianglesOccluded += mTrianglesLeft;
        stats.cubesDrawn -= mCubesLeft;
        stats.cubeFacesDrawn -= mFacesLeft;
        stats.geometryDraws = static_cast<std::uint64_t>(static_cast<std::int64_t>(stats.geometryDraws) - mDrawsLeft);
    }

private:
    /** The triangles of each of the draw's items (false: a page that does not view). */
    bool itemTriangles(const GeometryDraw& draw, std::vector<std::uint32_t>& out) const {
        if (!mClustered) {
            out.assign(draw.count, 1);
            return true;
        }
        const auto clusters = CachedClusterPage::clustersOf({draw.payload, draw.payloadBytes}, draw.first, draw.count);
        for (const storage::IndexedCluster& cluster : clusters)
            out.push_back(cluster.info.triangleCount);
        return clusters.size() == draw.count;
    }

    Renderer& mRenderer;
    const std::vector<BatchVisibility>& mVisible;
    const bool mClustered;
    std::vector<std::uint32_t> mItems;
    std::size_t mNext = 0;
    DrawList mScratch;
    std::uint64_t mTrianglesLeft = 0, mCubesLeft = 0, mFacesLeft = 0;
    std::int64_t mDrawsLeft = 0; ///< draws the walk merged less those the cut runs take (may be < 0)
};

} // namespace

Result<Frame> StreamingSession::renderOracle(const FrameContext& context) {
    Impl& s = *mImpl;
    if (s.cache && !s.completeFrames)
        return Status(ErrorCode::InvalidArgument, "the occlusion oracle needs every page mapped (no --cache-mb)");
    FrameContext plain = context;
    plain.occlusion.enabled = false;
    // What shows: the frame drawn whole, then each triangle and cube asked about.
    std::vector<BatchVisibility> visible;
    {
        KeepingSink keeping(*s.renderer);
        s.sinkOverride = &keeping;
        Frame first;
        double prefetchMs = 0.0;
        bool stalled = false;
        // Only the last try's batches: the ones before lacked pages (and their bytes may be gone).
        const Status drawn = s.untilComplete(first.stats, stalled, [&] {
            keeping.batches.clear();
            return s.frameToImage(plain, first, prefetchMs);
        });
        s.sinkOverride = nullptr;
        FF_RETURN_IF_ERROR(drawn);
        for (const DrawList& batch : keeping.batches)
            visible.push_back(s.renderer->visibleParts(batch));
    }
    VisibleOnlySink visibleOnly(*s.renderer, visible, isV2(s.scene()));
    Frame result;
    s.sinkOverride = &visibleOnly;
    const Status drawn = s.call(plain, result.stats, [&](double& prefetchMs, bool&) {
        FF_RETURN_IF_ERROR(s.frameToImage(plain, result, prefetchMs));
        visibleOnly.countInto(result.stats);
        return Status::ok();
    });
    s.sinkOverride = nullptr;
    FF_RETURN_IF_ERROR(drawn);
    return result;
}

Result<Frame> StreamingSession::renderComplete(const FrameContext& context) {
    Impl& s = *mImpl;
    Frame result;
    FF_RETURN_IF_ERROR(s.call(context, result.stats, [&](double& prefetchMs, bool& stalled) {
        return s.completeFrameToImage(context, result, prefetchMs, stalled);
    }));
    return result;
}

Result<FrameStats> StreamingSession::present(const FrameContext& context) {
    Impl& s = *mImpl;
    FrameStats stats;
    FF_RETURN_IF_ERROR(s.call(context, stats, [&](double& prefetchMs, bool& stalled) -> Status {
        const auto present = [&] {
            stats = {};
            return s.frame(context, FrameOutput::Window, stats, prefetchMs, [&] {
                return s.renderer->finishPresent(stats);
            });
        };
        return s.completeFrames ? s.untilComplete(stats, stalled, present) : present();
    }));
    return stats;
}

void StreamingSession::setPrefetchCamera(std::optional<Camera> camera) {
    mImpl->prefetchCamera = camera;
}

void StreamingSession::setCacheBudget(std::uint64_t bytes) {
    if (mImpl->cache)
        mImpl->cache->setBudget(std::max(bytes, mImpl->cache->maxPageBytes()));
}

Status StreamingSession::setGpuBudget(std::uint64_t bytes) {
    Impl& s = *mImpl;
    s.renderer.reset(); // frees the old page arena before the new one is allocated
    s.rendererOptions.gpuBudgetBytes = bytes;
    FF_ASSIGN_OR_RETURN(s.renderer, Renderer::create(s.scene(), s.rendererOptions, s.decodeStage.get()));
    return Status::ok();
}

const FrameTelemetry& StreamingSession::lastFrame() const noexcept {
    return mImpl->last;
}

SessionTotals StreamingSession::totals() const {
    const Impl& s = *mImpl;
    SessionTotals t;
    t.frames = static_cast<std::uint64_t>(s.frames);
    if (!s.cache)
        return t;
    const cache::PageCacheStats& c = s.cache->stats();
    t.requests = c.requests;
    t.cancelled = c.cancelled;
    t.refused = c.refused;
    t.noRoom = c.noRoom;
    t.evicted = c.evicted;
    t.dropped = c.dropped;
    t.bytesRead = c.bytesRead;
    t.uniqueBytes = s.counting->uniquePages() * s.scene().pageSize();
    t.peakResidentBytes = s.peakResidentBytes;
    t.budgetBytes = s.cache->budgetBytes();
    t.fetchToResidentP50 = c.fetchToResident.quantile(0.50);
    t.fetchToResidentP95 = c.fetchToResident.quantile(0.95);
    return t;
}

const std::vector<Status>& StreamingSession::newFailures() const noexcept {
    return mImpl->failures;
}

} // namespace ff::runtime
