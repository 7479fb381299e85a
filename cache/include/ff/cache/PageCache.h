#pragma once

// Layers of page access (runtime/StreamingSession.h draws the whole stack): IPageSource below is
// the source layer (where page bytes come from); PageCache is the resident layer (which pages
// are in memory, under a hard budget). The page cache: scene-file pages in memory under a hard
// byte budget, fetched in the background. Architecture (who calls what):
//
//   main thread:  beginFrame() -> tryGet(page) for what the frame wants to draw; request(page,
//                 priority) for what it lacks -> endFrame(): cancels requests not renewed this
//                 frame -> pump(maxCompletions): moves finished reads into the resident set,
//                 evicting least-recently-used pages not used by the current frame.
//   I/O threads:  take the highest-priority queued request, read it through IPageSource into
//                 a buffer, verify it, decode it (options.decoder, PageDecoder.h: the decode
//                 stage, on these threads, never on the main thread) and hand it to the
//                 completion queue. They never touch the resident set.
//
// Budget: resident bytes (pages as kept — decoded, with a decoder — handed out by tryGet and
// kept) never exceed budgetBytes; reads in flight hold their own buffers, bounded by maxInFlight
// pages of at most maxDecodedBytes each. A request the budget has no
// room for beside the frames' pages is not read (readOnlyWhatFits); a completion that cannot
// fit without evicting a page the current frame uses or a pinned page is dropped (and counted),
// never forced in. The one exception is setBudget() below the bytes the current frame (or the
// pins) hold: see there.
//
// Pins (pin()): a page's bytes can also be held by an RAII storage::PagePin, for work that
// outlives a frame: a pinned page is never evicted, and its bytes outlive even the cache until
// the pin is released, on any thread.
//
// Page life cycle (state()):  Absent -request-> Pending -read ok, fits-> Resident -evict-> Absent
//                             Pending -not renewed by endFrame()/displaced/dropped-> Absent
//                             Pending -read error-> Failed (final: never read again)
//
// Threads: the creating thread is "the main thread"; every method but the destructor asserts
// it runs there. The cache owns options.ioThreads I/O threads, which share only the request
// queue and the completion queue with it (under one mutex) and never touch the resident set.

#include <ff/cache/LatencyHistogram.h>
#include <ff/cache/PageDecoder.h>
#include <ff/storage/PageSource.h>
#include <ff/storage/Status.h>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>

namespace ff::cache {

/** Where pages come from (storage/PageSource.h): the cache reads through it on I/O threads. */
using storage::IPageSource;

struct PageCacheOptions {
    std::uint64_t budgetBytes = 256ull << 20; ///< hard limit on resident page bytes
    unsigned ioThreads = 2;
    /** Requests queued, being read or waiting for pump() at once (>= 1): bounds the memory
     *  held outside the budget to maxInFlight pages. When full, a new request displaces the
     *  lowest-priority queued one if its priority is higher, else it is refused (stats.refused)
     *  and the caller asks again next frame. */
    std::uint32_t maxInFlight = 64;
    /** When a completion needs room, evict down to (1 - hysteresis) x budget rather than to
     *  exactly what it needs, so a working set at the edge of the budget does not evict one
     *  page per install, every frame. In [0, 1); 0 disables. */
    double hysteresis = 0.05;
    /** Read only what can be installed: a new request is not queued (stats.noRoom; the caller
     *  asks again next frame) while the pages the frames hold — the larger of the previous
     *  frame's and the current frame's so far — plus the reads under way leave no room for it in
     *  the budget; as with maxInFlight, it displaces a less urgent queued request instead. A
     *  frame that needs more than the budget then keeps the coarser cut it has, reading nothing,
     *  rather than reading pages that can only be dropped and asking for them again every frame
     *  (an orbit at the budget's edge read 8-22x its unique bytes). Off (the default: the
     *  cache reads what it is asked for), a completion without room is dropped instead; the
     *  viewer's streaming sessions turn it on. */
    bool readOnlyWhatFits = false;
    /** The decode stage: what each page becomes on the I/O thread that read it before it is
     *  kept (null: pages are kept as read). The budget counts the decoded bytes; a read in
     *  flight is counted at the decoder's maxDecodedBytes until it is installed. */
    std::shared_ptr<IPageDecoder> decoder;
};

enum class PageState { Resident, Pending, Failed, Absent };

/** Counters since creation (a frame's figures are the difference of two snapshots), plus the
 *  current residentBytes and inFlight. */
struct PageCacheStats {
    std::uint64_t hits = 0;      ///< tryGet found the page resident
    std::uint64_t misses = 0;    ///< tryGet did not
    std::uint64_t requests = 0;  ///< new requests queued
    std::uint64_t refused = 0;   ///< new requests not queued: maxInFlight reached
    std::uint64_t noRoom = 0;    ///< new requests not queued: no room in the budget (readOnlyWhatFits)
    std::uint64_t cancelled = 0; ///< queued requests dropped: not renewed, or displaced
    std::uint64_t completed = 0; ///< reads moved into the resident set
    std::uint64_t dropped = 0;   ///< reads that could not fit the budget
    std::uint64_t failed = 0;    ///< pages that failed (I/O or checksum), each counted once
    std::uint64_t evicted = 0;
    std::uint64_t bytesRead = 0;
    std::uint64_t bytesDecoded = 0; ///< bytes the decoder made of the pages read (0 without one)
    std::uint64_t residentBytes = 0;
    std::uint64_t peakResidentBytes = 0;
    std::uint64_t inFlight = 0; ///< requests queued, being read or waiting for pump()
    /** Fetch to resident: from the request() that queued a read to the pump() that installed
     *  it, for every page installed (a read cancelled and asked for again counts from the new
     *  request). It includes the wait for the next pump(), as frames see it. */
    LatencyHistogram fetchToResident;
};

/**
 * See the architecture note above. Main-thread methods assert they are called from the thread
 * that created the cache. Destruction cancels queued reads, waits for the reads already running
 * (IPageSource::readPage must return), joins the I/O threads and frees every buffer; it may run
 * on any thread once no other call on the cache is running.
 */
class PageCache {
public:
    /** Starts the I/O threads. Errors: InvalidArgument when the budget cannot hold even one
     *  page (maxPageBytes()), or when ioThreads or maxInFlight is 0 or hysteresis is outside [0, 1). */
    [[nodiscard]] static Result<std::unique_ptr<PageCache>>
    create(std::shared_ptr<IPageSource> source, const PageCacheOptions& options);
    ~PageCache();
    PageCache(const PageCache&) = delete;
    PageCache& operator=(const PageCache&) = delete;

    /** Starts a frame: pages used by the previous frame become evictable again (and, after a
     *  setBudget() below them, are evicted down to the budget now). */
    void beginFrame();
    /** The bytes of a resident page as kept (as read: pageSize bytes; else what the decoder
     *  made of them), marked used by this frame (not evictable until the next
     *  beginFrame). The span stays valid until then. Counts a hit or a miss. When the page is
     *  resident and `firstUse` is given, *firstUse tells whether this is the frame's first
     *  tryGet of it (callers count the distinct pages a frame used). */
    std::optional<std::span<const std::byte>> tryGet(std::uint64_t page, bool* firstUse = nullptr);
    /** A pin of a resident page (empty if it is not resident): the page is not evicted, and its
     *  bytes (as tryGet() gives them) stay valid, until the pin is released — on any thread,
     *  even after the cache is gone. Not a use by the frame (no hit, no LRU touch). Pinned
     *  pages count in the budget: while pins hold it, completions that do not fit are dropped,
     *  and after setBudget() residentBytes may stay above budgetBytes until they are released. */
    [[nodiscard]] storage::PagePin pin(std::uint64_t page);
    /** Asks for a page; a higher priority is fetched first (equal priorities: first asked, first
     *  read). Renewing a request updates its priority and keeps it alive through endFrame().
     *  No-op for resident or failed pages. A page >= the source's pageCount fails at once
     *  (Failed, InvalidArgument). `priority` must not be NaN. */
    void request(std::uint64_t page, float priority);
    PageState state(std::uint64_t page) const;
    /** Why page `page` failed (the IPageSource error, e.g. Corrupt "page 12: checksum
     *  mismatch ..."); nullopt unless state(page) is Failed. */
    std::optional<Status> failure(std::uint64_t page) const;
    /** Cancels queued requests that this frame did not renew (request() since beginFrame());
     *  reads already running are not cancelled: they complete and are installed if they fit. */
    void endFrame();
    /** Handles at most maxCompletions finished reads, oldest first: each is installed (evicting
     *  as needed), dropped (no room without evicting a page of the current frame) or marked
     *  Failed. Returns how many were installed. Never blocks on I/O. */
    std::size_t pump(std::size_t maxCompletions);
    /** Blocks until nothing is queued or in flight (tests, --sync mode), then pumps all. */
    void drain();

    const PageCacheStats& stats() const noexcept;
    std::uint64_t budgetBytes() const noexcept;
    /** The most bytes one resident page takes: the source's page size, or the decoder's
     *  maxDecodedBytes. */
    std::uint64_t maxPageBytes() const noexcept;
    /** Changes the budget (at least maxPageBytes(): asserted), evicting as needed, never pages
     *  used by the current frame or pinned. Should those alone exceed the new budget,
     *  residentBytes stays above budgetBytes until the next beginFrame() (or, for pinned pages,
     *  the first after their pins are released), which evicts down to it; no completion is
     *  installed meanwhile. This is the only time residentBytes > budgetBytes. */
    void setBudget(std::uint64_t bytes);

private:
    struct Impl;
    explicit PageCache(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> mImpl;
};

} // namespace ff::cache
