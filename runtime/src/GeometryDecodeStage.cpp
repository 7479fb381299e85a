#include "GeometryDecodeStage.h"

#include <ff/storage/Assert.h>
#include <ff/storage/ClusterPage.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <string>
#include <system_error>
#include <thread>
#include <unordered_map>
#include <unordered_set>

namespace ff::runtime {

namespace {

struct Job {
    std::uint64_t page = 0;
    storage::PagePin pin;
};

struct Finished {
    std::uint64_t page = 0;
    Result<DecodedGeometry> geometry;
    double seconds = 0.0;
};

/** A page the stage knows of, main thread only. */
struct Entry {
    bool ready = false;          ///< decoded (else queued or being decoded)
    std::uint64_t lastAsked = 0; ///< the frame that last called prepare() for it
    DecodedGeometry geometry;
};

} // namespace

struct GeometryDecodeStage::Impl {
    cache::PageCache& cache;
    const std::vector<storage::PositionGrid> grids;
    const std::uint64_t maxDecodedBytes;
    const std::uint32_t capacity;

    // Main thread.
    std::unordered_map<std::uint64_t, Entry> entries;
    std::unordered_set<std::uint64_t> failedPages;
    std::vector<Status> failures;
    std::uint64_t frame = 0;
    DecodeStageStats stats;

    // Shared with the decode threads, under `mutex`.
    std::mutex mutex;
    std::condition_variable work; ///< a job was queued, or stop
    std::condition_variable idle; ///< a job finished
    std::deque<Job> queue;
    std::vector<Finished> finished;
    unsigned running = 0;
    bool stop = false;
    std::vector<std::thread> threads;

    Impl(cache::PageCache& c,
         std::vector<storage::PositionGrid> g,
         std::uint32_t pageSize,
         std::uint32_t cap)
        : cache(c)
        , grids(std::move(g))
        , maxDecodedBytes(storage::maxDecodedClusterBytes(pageSize))
        , capacity(std::max<std::uint32_t>(cap, 1)) {}

    void decodeLoop();
    Finished decodeOne(Job& job) const;
};

Finished GeometryDecodeStage::Impl::decodeOne(Job& job) const {
    const auto start = std::chrono::steady_clock::now();
    const std::span<const std::byte> bytes = job.pin.bytes();
    Finished out{job.page, Status(ErrorCode::Corrupt, ""), 0.0};
    if (bytes.size() < sizeof(storage::PageTrailer)) {
        out.geometry =
                Status(ErrorCode::Corrupt,
                       "page " + std::to_string(job.page) + ": not a cached cluster page");
    } else {
        const Result<CachedClusterPage> page =
                CachedClusterPage::view(bytes.first(bytes.size() - sizeof(storage::PageTrailer)));
        out.geometry = page ? decodeCachedPage(*page, grids, maxDecodedBytes)
                            : Result<DecodedGeometry>(page.status());
        if (!out.geometry)
            out.geometry = out.geometry.status().withContext("page " + std::to_string(job.page));
    }
    job.pin.reset(); // the cache may evict the page from now on
    out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return out;
}

void GeometryDecodeStage::Impl::decodeLoop() {
    std::unique_lock lock(mutex);
    for (;;) {
        work.wait(lock, [this] { return stop || !queue.empty(); });
        if (stop)
            return;
        Job job = std::move(queue.front());
        queue.pop_front();
        ++running;
        lock.unlock();
        Finished result = decodeOne(job);
        lock.lock();
        finished.push_back(std::move(result));
        --running;
        idle.notify_all();
    }
}

GeometryDecodeStage::GeometryDecodeStage(
        cache::PageCache& cache,
        std::vector<storage::PositionGrid> grids,
        std::uint32_t pageSize,
        const DecodeStageOptions& options)
    : mImpl(std::make_unique<Impl>(cache, std::move(grids), pageSize, options.capacity)) {}

Result<std::unique_ptr<GeometryDecodeStage>> GeometryDecodeStage::create(
        cache::PageCache& cache,
        std::vector<storage::PositionGrid> grids,
        std::uint32_t pageSize,
        const DecodeStageOptions& options) {
    std::unique_ptr<GeometryDecodeStage> stage(
            new GeometryDecodeStage(cache, std::move(grids), pageSize, options));
    const unsigned threads = std::max(options.threads, 1u);
    try {
        for (unsigned t = 0; t < threads; ++t)
            stage->mImpl->threads.emplace_back(
                    [impl = stage->mImpl.get()] { impl->decodeLoop(); });
    } catch (const std::system_error& error) {
        // The stage's destructor stops and joins the threads already started.
        return Status(
                ErrorCode::Internal, std::string("cannot start a decode thread: ") + error.what());
    }
    return stage;
}

GeometryDecodeStage::~GeometryDecodeStage() {
    {
        const std::lock_guard lock(mImpl->mutex);
        mImpl->stop = true;
        mImpl->queue.clear(); // releases the queued pins
    }
    mImpl->work.notify_all();
    for (std::thread& t : mImpl->threads)
        t.join();
}

void GeometryDecodeStage::beginFrame() {
    Impl& s = *mImpl;
    const std::uint64_t lastFrame = s.frame++;
    std::vector<Finished> finished;
    {
        const std::lock_guard lock(s.mutex);
        finished.swap(s.finished);
        // Queued pages the frame before did not ask for again are not wanted any more.
        const auto unwanted = [&](const Job& job) {
            const auto it = s.entries.find(job.page);
            if (it == s.entries.end() || it->second.lastAsked >= lastFrame)
                return false;
            s.entries.erase(it);
            ++s.stats.cancelled;
            return true;
        };
        s.queue.erase(std::remove_if(s.queue.begin(), s.queue.end(), unwanted), s.queue.end());
    }
    // Decoded pages not asked for in the frame before are freed (uploaded ones already are).
    for (auto it = s.entries.begin(); it != s.entries.end();) {
        Entry& e = it->second;
        if (e.ready && e.lastAsked < lastFrame) {
            ++s.stats.dropped;
            s.stats.heldBytes -= e.geometry.size();
            it = s.entries.erase(it);
        } else {
            ++it;
        }
    }
    for (Finished& f : finished) {
        s.stats.decodeSeconds += f.seconds;
        const auto it = s.entries.find(f.page);
        FF_ASSERT(it != s.entries.end() && !it->second.ready);
        if (!f.geometry) {
            s.entries.erase(it);
            s.failedPages.insert(f.page);
            s.failures.push_back(f.geometry.status());
            ++s.stats.failed;
            continue;
        }
        if (it->second.lastAsked < lastFrame) { // asked for no more: no use keeping it
            s.entries.erase(it);
            ++s.stats.dropped;
            continue;
        }
        Entry& e = it->second;
        e.ready = true;
        e.geometry = std::move(*f.geometry);
        ++s.stats.decoded;
        s.stats.decodedBytes += e.geometry.size();
        s.stats.heldBytes += e.geometry.size();
        s.stats.peakHeldBytes = std::max(s.stats.peakHeldBytes, s.stats.heldBytes);
    }
}

bool GeometryDecodeStage::prepare(std::uint64_t page) {
    Impl& s = *mImpl;
    if (const auto it = s.entries.find(page); it != s.entries.end()) {
        it->second.lastAsked = s.frame;
        return it->second.ready;
    }
    if (s.failedPages.contains(page))
        return false;
    if (s.entries.size() >= s.capacity) {
        ++s.stats.refused;
        return false;
    }
    storage::PagePin pin = s.cache.pin(page);
    if (pin.empty())
        return false; // not resident: the traversal asks the cache for it
    s.entries[page].lastAsked = s.frame;
    ++s.stats.requested;
    {
        const std::lock_guard lock(s.mutex);
        s.queue.push_back({page, std::move(pin)});
    }
    s.work.notify_one();
    return false;
}

const DecodedGeometry* GeometryDecodeStage::decoded(std::uint64_t page) const {
    const auto it = mImpl->entries.find(page);
    return it != mImpl->entries.end() && it->second.ready ? &it->second.geometry : nullptr;
}

void GeometryDecodeStage::uploaded(std::uint64_t page) {
    Impl& s = *mImpl;
    const auto it = s.entries.find(page);
    if (it == s.entries.end() || !it->second.ready)
        return;
    // The GPU has its copy (glBufferSubData copies before it returns): the room is free now,
    // for pages this frame still asks for.
    s.stats.heldBytes -= it->second.geometry.size();
    s.entries.erase(it);
}

void GeometryDecodeStage::drain() {
    std::unique_lock lock(mImpl->mutex);
    mImpl->idle.wait(lock, [this] { return mImpl->queue.empty() && mImpl->running == 0; });
}

std::vector<Status> GeometryDecodeStage::takeFailures() {
    return std::exchange(mImpl->failures, {});
}

const DecodeStageStats& GeometryDecodeStage::stats() const noexcept {
    return mImpl->stats;
}

} // namespace ff::runtime
