#include "RequestQueue.h"

#include <ff/cache/PageCache.h>
#include <ff/cache/PageLru.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <deque>
#include <limits>
#include <mutex>
#include <string>
#include <system_error>
#include <thread>
#include <unordered_map>
#include <utility>
#include <vector>

namespace ff::cache {

namespace {

constexpr std::uint64_t kNeverUsed = std::numeric_limits<std::uint64_t>::max();

/** A finished read on its way from an I/O thread to the main thread. */
struct Completion {
    std::uint64_t page = 0;
    PageBuffer bytes; ///< as read, or decoded; empty when `status` is an error
    Status status;
};

/**
 * What the I/O threads share with the main thread, all guarded by `mutex`. Held through a
 * shared_ptr that each I/O thread captures by value, so a thread never refers to the cache.
 */
struct SharedQueues {
    std::mutex mutex;
    std::condition_variable workAvailable; ///< queue not empty, or stopping
    std::condition_variable readFinished;  ///< a read moved to `completions` (drain() waits)
    RequestQueue queue;                    ///< requests no thread has taken yet
    std::deque<Completion> completions;    ///< finished reads, oldest first, for pump()
    unsigned running = 0;                  ///< reads taken from `queue`, not yet in `completions`
    bool stopping = false;
};

/** Reads page `page` and, with a decoder, decodes it: what one worker does outside the lock. */
Completion readAndDecode(std::uint64_t page, IPageSource& source, IPageDecoder* decoder) {
    const std::size_t pageSize = source.pageSize();
    Completion done{page, {std::make_unique_for_overwrite<std::byte[]>(pageSize), pageSize}, Status::ok()};
    done.status = source.readPage(page, {done.bytes.bytes.get(), pageSize});
    if (done.status.isOk() && decoder != nullptr) {
        done.status = decoder->decode(page, done.bytes);
        const std::size_t most = decoder->maxDecodedBytes(source.pageSize());
        if (done.status.isOk() && (done.bytes.bytes == nullptr || done.bytes.size > most))
            done.status = Status(
                    ErrorCode::Internal,
                    "page " + std::to_string(page) + ": decoded to " + std::to_string(done.bytes.size) +
                            " bytes, the decoder promised at most " + std::to_string(most));
    }
    if (!done.status.isOk())
        done.bytes = {};
    return done;
}

/** One worker thread: take the highest-priority request, read and decode it outside the lock,
 *  hand it over. */
void runIoThread(SharedQueues& shared, IPageSource& source, IPageDecoder* decoder) {
    std::unique_lock lock(shared.mutex);
    for (;;) {
        shared.workAvailable.wait(
                lock, [&shared] { return shared.stopping || !shared.queue.empty(); });
        if (shared.stopping)
            return;
        const std::uint64_t page = *shared.queue.popHighest();
        ++shared.running;
        lock.unlock();

        Completion done = readAndDecode(page, source, decoder);

        lock.lock();
        --shared.running;
        shared.completions.push_back(std::move(done));
        shared.readFinished.notify_all();
    }
}

/** Main-thread bookkeeping of one page that is not Absent. */
struct PageEntry {
    PageState state = PageState::Absent;
    /** Resident: the page as kept. Shared with its pins (pin()): while one lives, use_count()
     *  > 1 and the page is not evicted. Pins are made on the main thread only, so a count of 1
     *  read there stays 1 until the main thread pins again. */
    std::shared_ptr<const PageBuffer> bytes;
    std::uint64_t usedFrame = kNeverUsed; ///< Resident: last frame whose tryGet() returned it
    std::chrono::steady_clock::time_point requested; ///< Pending: when request() queued it
    Status failure;                       ///< Failed: why
};

} // namespace

struct PageCache::Impl {
    std::shared_ptr<IPageSource> source;
    PageCacheOptions options;
    std::uint32_t pageSize = 0;
    /** The most one resident page takes: pageSize, or what the decoder may make of one. */
    std::uint64_t maxPageBytes = 0;
    std::uint64_t pageCount = 0;
    std::thread::id owner = std::this_thread::get_id();

    std::shared_ptr<SharedQueues> shared = std::make_shared<SharedQueues>();
    std::vector<std::thread> ioThreads;

    // ---- main thread only ----
    std::unordered_map<std::uint64_t, PageEntry> entries; ///< pages not Absent
    PageLru lru;                                          ///< resident pages
    PageCacheStats stats;
    std::uint64_t frame = 0;
    std::uint64_t frameBytes = 0; ///< resident bytes tryGet() handed out this frame
    std::uint64_t previousFrameBytes = 0; ///< frameBytes of the frame before
    std::uint64_t inFlight = 0;   ///< Pending pages: queued, being read or awaiting pump()
    std::vector<std::uint64_t> scratchPages;    ///< reused by endFrame()
    std::vector<Completion> scratchCompletions; ///< reused by pump()

    ~Impl() {
        {
            std::lock_guard lock(shared->mutex);
            shared->stopping = true;
            shared->queue.clear();
        }
        shared->workAvailable.notify_all();
        for (std::thread& thread : ioThreads)
            thread.join();
        // Completions not pumped and resident pages are freed with `shared` and `entries`.
    }

    bool onOwnerThread() const { return std::this_thread::get_id() == owner; }

    /** Where eviction aims when a completion of `bytes` needs room: (1 - hysteresis) x budget
     *  after the install, but never less room than the one page being installed. */
    std::uint64_t lowWater(std::uint64_t bytes) const {
        const std::uint64_t budget = options.budgetBytes;
        const auto lowBudget = static_cast<std::uint64_t>(
                static_cast<double>(budget) * (1.0 - options.hysteresis));
        const std::uint64_t afterInstall = std::min(lowBudget, budget);
        return afterInstall >= bytes ? afterInstall - bytes : 0;
    }

    static bool pinned(const PageEntry& entry) { return entry.bytes.use_count() > 1; }

    void evict(std::uint64_t page) {
        const auto it = entries.find(page);
        FF_ASSERT(it != entries.end() && it->second.state == PageState::Resident);
        FF_ASSERT(it->second.usedFrame != frame && !pinned(it->second));
        stats.residentBytes -= it->second.bytes->size;
        entries.erase(it);
        lru.erase(page);
        ++stats.evicted;
    }

    /** Evicts least-recently-used pages neither used by the current frame nor pinned until
     *  residentBytes <= target or none of those is left. */
    void evictDownTo(std::uint64_t target) {
        // Pages used this frame were touched by tryGet(), so the walk from the oldest end meets
        // evictable pages first; frameBytes tells when none is left without walking.
        while (stats.residentBytes > target && stats.residentBytes > frameBytes) {
            const auto victim = lru.oldestWhereNot([this](std::uint64_t page) {
                const PageEntry& entry = entries.find(page)->second;
                return entry.usedFrame == frame || pinned(entry);
            });
            if (!victim)
                return; // the rest is pinned
            evict(*victim);
        }
    }

    /** Installs, drops or fails one completion; true if installed. */
    bool handle(Completion& done) {
        const auto it = entries.find(done.page);
        // Only queued requests are ever cancelled, so a finished read's page is still Pending.
        FF_ASSERT(it != entries.end() && it->second.state == PageState::Pending);
        PageEntry& entry = it->second;
        --inFlight;

        if (!done.status.isOk()) {
            entry.state = PageState::Failed;
            entry.failure = std::move(done.status);
            ++stats.failed;
            return false;
        }
        stats.bytesRead += pageSize;
        const std::uint64_t bytes = done.bytes.size;
        if (options.decoder != nullptr)
            stats.bytesDecoded += bytes;
        const std::uint64_t budget = options.budgetBytes;
        if (stats.residentBytes + bytes > budget) {
            // Decide before evicting anything: a page that cannot fit even after evicting every
            // page the current frame does not use is dropped, and nothing is evicted for it.
            // (Pinned pages are found only while evicting: with pins, a page may be dropped
            // after some eviction.)
            if (frameBytes + bytes > budget) {
                entries.erase(it);
                ++stats.dropped;
                return false;
            }
            evictDownTo(std::min(lowWater(bytes), budget - bytes));
            if (stats.residentBytes + bytes > budget) { // pins hold the rest
                entries.erase(it);
                ++stats.dropped;
                return false;
            }
        }
        entry.state = PageState::Resident;
        stats.fetchToResident.add(
                std::chrono::duration<double>(std::chrono::steady_clock::now() - entry.requested).count());
        entry.bytes = std::make_shared<const PageBuffer>(std::move(done.bytes));
        entry.usedFrame = kNeverUsed;
        lru.touch(done.page);
        stats.residentBytes += bytes;
        stats.peakResidentBytes = std::max(stats.peakResidentBytes, stats.residentBytes);
        ++stats.completed;
        return true;
    }
};

PageCache::PageCache(std::unique_ptr<Impl> impl)
    : mImpl(std::move(impl)) {}

PageCache::~PageCache() = default;

Result<std::unique_ptr<PageCache>>
PageCache::create(std::shared_ptr<IPageSource> source, const PageCacheOptions& options) {
    FF_ASSERT(source != nullptr);
    const std::uint32_t pageSize = source->pageSize();
    FF_ASSERT(pageSize > 0);
    const std::uint64_t maxPageBytes =
            options.decoder ? std::max<std::uint64_t>(options.decoder->maxDecodedBytes(pageSize), pageSize) : pageSize;
    if (options.budgetBytes < maxPageBytes)
        return Status{
                ErrorCode::InvalidArgument,
                "page cache budget of " + std::to_string(options.budgetBytes) +
                        " bytes cannot hold one page of " + std::to_string(maxPageBytes) +
                        (maxPageBytes > pageSize ? " bytes decoded" : " bytes")};
    if (options.ioThreads == 0)
        return Status{ErrorCode::InvalidArgument, "page cache needs at least one I/O thread"};
    if (options.maxInFlight == 0)
        return Status{ErrorCode::InvalidArgument, "page cache maxInFlight must be at least 1"};
    if (!(options.hysteresis >= 0.0 && options.hysteresis < 1.0))
        return Status{
                ErrorCode::InvalidArgument,
                "page cache hysteresis " + std::to_string(options.hysteresis) +
                        " is outside [0, 1)"};

    auto impl = std::make_unique<Impl>();
    impl->source = source;
    impl->options = options;
    impl->pageSize = pageSize;
    impl->maxPageBytes = maxPageBytes;
    impl->pageCount = source->pageCount();
    impl->ioThreads.reserve(options.ioThreads);
    const std::shared_ptr<SharedQueues> shared = impl->shared;
    try {
        for (unsigned i = 0; i < options.ioThreads; ++i)
            impl->ioThreads.emplace_back([shared, source, decoder = options.decoder] {
                runIoThread(*shared, *source, decoder.get());
            });
    } catch (const std::system_error& error) {
        // ~Impl stops and joins the threads already started.
        return Status{
                ErrorCode::Internal,
                std::string("cannot start a page cache I/O thread: ") + error.what()};
    }
    return std::unique_ptr<PageCache>(new PageCache(std::move(impl)));
}

void PageCache::beginFrame() {
    Impl& m = *mImpl;
    FF_ASSERT(m.onOwnerThread());
    ++m.frame;
    m.previousFrameBytes = m.frameBytes;
    m.frameBytes = 0;
    // After a setBudget() below what the previous frame held: nothing is protected now.
    if (m.stats.residentBytes > m.options.budgetBytes)
        m.evictDownTo(m.options.budgetBytes);
}

std::optional<std::span<const std::byte>> PageCache::tryGet(std::uint64_t page, bool* firstUse) {
    Impl& m = *mImpl;
    FF_ASSERT(m.onOwnerThread());
    const auto it = m.entries.find(page);
    if (it == m.entries.end() || it->second.state != PageState::Resident) {
        ++m.stats.misses;
        return std::nullopt;
    }
    ++m.stats.hits;
    PageEntry& entry = it->second;
    const bool first = entry.usedFrame != m.frame;
    if (first) {
        entry.usedFrame = m.frame;
        m.frameBytes += entry.bytes->size;
    }
    if (firstUse)
        *firstUse = first;
    m.lru.touch(page);
    return entry.bytes->view();
}

storage::PagePin PageCache::pin(std::uint64_t page) {
    Impl& m = *mImpl;
    FF_ASSERT(m.onOwnerThread());
    const auto it = m.entries.find(page);
    if (it == m.entries.end() || it->second.state != PageState::Resident)
        return {};
    const std::shared_ptr<const PageBuffer>& kept = it->second.bytes;
    return storage::PagePin(kept->view(), kept);
}

void PageCache::request(std::uint64_t page, float priority) {
    Impl& m = *mImpl;
    FF_ASSERT(m.onOwnerThread());
    FF_ASSERT(!std::isnan(priority));
    const auto it = m.entries.find(page);
    if (it != m.entries.end()) {
        if (it->second.state == PageState::Pending) {
            // Still queued: new priority, alive through endFrame(). Already taken by an I/O
            // thread: nothing to renew, the read completes anyway.
            std::lock_guard lock(m.shared->mutex);
            m.shared->queue.renew(page, priority, m.frame);
        }
        return; // Resident or Failed: no-op
    }
    if (page >= m.pageCount) {
        PageEntry& entry = m.entries[page];
        entry.state = PageState::Failed;
        entry.failure =
                Status{ErrorCode::InvalidArgument,
                       "page " + std::to_string(page) + ": beyond the source's " +
                               std::to_string(m.pageCount) + " pages"};
        ++m.stats.failed;
        return;
    }
    // Room for one more read beside what the frames hold: a still or slowly moving camera uses
    // about what it used last frame, so that is claimed too, not only what this frame has used so far.
    const std::uint64_t claimed = std::max(m.previousFrameBytes, m.frameBytes) + (m.inFlight + 1) * m.maxPageBytes;
    const bool noRoom = m.options.readOnlyWhatFits && claimed > m.options.budgetBytes;
    {
        std::lock_guard lock(m.shared->mutex);
        if (m.inFlight >= m.options.maxInFlight || noRoom) {
            // Full: displace the least urgent queued request if this one is more urgent.
            const auto lowest = m.shared->queue.lowest();
            if (!lowest || lowest->second >= priority) {
                ++(noRoom ? m.stats.noRoom : m.stats.refused);
                return;
            }
            m.shared->queue.erase(lowest->first);
            m.entries.erase(lowest->first);
            --m.inFlight;
            ++m.stats.cancelled;
        }
        m.shared->queue.push(page, priority, m.frame);
    }
    m.shared->workAvailable.notify_one();
    PageEntry& entry = m.entries[page];
    entry.state = PageState::Pending;
    entry.requested = std::chrono::steady_clock::now();
    ++m.inFlight;
    ++m.stats.requests;
    m.stats.inFlight = m.inFlight;
}

PageState PageCache::state(std::uint64_t page) const {
    const Impl& m = *mImpl;
    FF_ASSERT(m.onOwnerThread());
    const auto it = m.entries.find(page);
    return it == m.entries.end() ? PageState::Absent : it->second.state;
}

std::optional<Status> PageCache::failure(std::uint64_t page) const {
    const Impl& m = *mImpl;
    FF_ASSERT(m.onOwnerThread());
    const auto it = m.entries.find(page);
    if (it == m.entries.end() || it->second.state != PageState::Failed)
        return std::nullopt;
    return it->second.failure;
}

void PageCache::endFrame() {
    Impl& m = *mImpl;
    FF_ASSERT(m.onOwnerThread());
    m.scratchPages.clear();
    {
        std::lock_guard lock(m.shared->mutex);
        m.shared->queue.removeNotRenewedIn(m.frame, m.scratchPages);
    }
    for (const std::uint64_t page : m.scratchPages)
        m.entries.erase(page);
    m.inFlight -= m.scratchPages.size();
    m.stats.cancelled += m.scratchPages.size();
    m.stats.inFlight = m.inFlight;
}

std::size_t PageCache::pump(std::size_t maxCompletions) {
    Impl& m = *mImpl;
    FF_ASSERT(m.onOwnerThread());
    m.scratchCompletions.clear();
    {
        std::lock_guard lock(m.shared->mutex);
        auto& completions = m.shared->completions;
        while (m.scratchCompletions.size() < maxCompletions && !completions.empty()) {
            m.scratchCompletions.push_back(std::move(completions.front()));
            completions.pop_front();
        }
    }
    std::size_t installed = 0;
    for (Completion& done : m.scratchCompletions) {
        if (m.handle(done))
            ++installed;
    }
    m.scratchCompletions.clear(); // frees the buffers of dropped reads
    m.stats.inFlight = m.inFlight;
    return installed;
}

void PageCache::drain() {
    Impl& m = *mImpl;
    FF_ASSERT(m.onOwnerThread());
    {
        SharedQueues& shared = *m.shared;
        std::unique_lock lock(shared.mutex);
        shared.readFinished.wait(
                lock, [&shared] { return shared.queue.empty() && shared.running == 0; });
    }
    pump(std::numeric_limits<std::size_t>::max());
}

const PageCacheStats& PageCache::stats() const noexcept {
    FF_ASSERT(mImpl->onOwnerThread());
    return mImpl->stats;
}

std::uint64_t PageCache::budgetBytes() const noexcept {
    FF_ASSERT(mImpl->onOwnerThread());
    return mImpl->options.budgetBytes;
}

std::uint64_t PageCache::maxPageBytes() const noexcept {
    return mImpl->maxPageBytes;
}

void PageCache::setBudget(std::uint64_t bytes) {
    Impl& m = *mImpl;
    FF_ASSERT(m.onOwnerThread());
    FF_ASSERT(bytes >= m.maxPageBytes);
    m.options.budgetBytes = bytes;
    if (m.stats.residentBytes > bytes)
        m.evictDownTo(bytes);
}

} // namespace ff::cache
