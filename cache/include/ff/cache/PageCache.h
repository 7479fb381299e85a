#pragma once

// The page cache: scene-file pages in memory under a hard byte budget, fetched in the
// background. Architecture (who calls what):
//
//   main thread:  beginFrame() -> tryGet(page) for what the frame wants to draw; request(page,
//                 priority) for what it lacks -> endFrame(): cancels requests not renewed this
//                 frame -> pump(maxCompletions): moves finished reads into the resident set,
//                 evicting least-recently-used pages not used by the current frame.
//   I/O threads:  take the highest-priority queued request, read it through IPageSource into
//                 a buffer, verify it, and hand it to the completion queue. They never touch
//                 the resident set.
//
// Budget: resident bytes (pages handed out by tryGet and kept) never exceed budgetBytes; reads
// in flight hold their own buffers, bounded by maxInFlight pages. A completion that cannot fit
// without evicting a page the current frame uses is dropped (and counted), never forced in.

#include <ff/storage/Status.h>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>

namespace ff::cache {

/** Where pages come from. Implementations must be safe to call from several threads at once. */
class IPageSource {
public:
    virtual ~IPageSource() = default;
    virtual std::uint32_t pageSize() const = 0;
    virtual std::uint64_t pageCount() const = 0;
    /** Reads and verifies page `index` into `out` (pageSize bytes). Called on I/O threads. */
    [[nodiscard]] virtual Status readPage(std::uint64_t index, std::span<std::byte> out) = 0;
};

struct PageCacheOptions {
    std::uint64_t budgetBytes = 256ull << 20; ///< hard limit on resident page bytes
    unsigned ioThreads = 2;
    std::uint32_t maxInFlight = 64; ///< reads queued or running at once
    /** When a completion needs room, evict down to (1 - hysteresis) x budget rather than to
     *  exactly what it needs, so a working set at the edge of the budget does not evict one
     *  page per install, every frame. 0 disables. */
    double hysteresis = 0.05;
};

enum class PageState { Resident, Pending, Failed, Absent };

/** Per-frame and cumulative counters. */
struct PageCacheStats {
    std::uint64_t hits = 0;        ///< tryGet found the page resident
    std::uint64_t misses = 0;      ///< tryGet did not
    std::uint64_t requests = 0;    ///< new requests queued
    std::uint64_t cancelled = 0;   ///< requests dropped because no frame renewed them
    std::uint64_t completed = 0;   ///< reads moved into the resident set
    std::uint64_t dropped = 0;     ///< reads that could not fit the budget
    std::uint64_t failed = 0;      ///< reads that failed (I/O or checksum)
    std::uint64_t evicted = 0;
    std::uint64_t bytesRead = 0;
    std::uint64_t residentBytes = 0;
    std::uint64_t peakResidentBytes = 0;
    std::uint64_t inFlight = 0;
};

/**
 * See the architecture note above. Main-thread methods assert they are called from the thread
 * that created the cache. Destruction cancels queued reads and joins the I/O threads.
 */
class PageCache {
public:
    /** Errors: InvalidArgument when the budget cannot hold even one page. */
    [[nodiscard]] static Result<std::unique_ptr<PageCache>> create(
            std::shared_ptr<IPageSource> source, const PageCacheOptions& options);
    ~PageCache();
    PageCache(const PageCache&) = delete;
    PageCache& operator=(const PageCache&) = delete;

    void beginFrame();
    /** The bytes of a resident page, marked used by this frame (not evictable until the next
     *  beginFrame). The span stays valid until then. Counts a hit or a miss. */
    std::optional<std::span<const std::byte>> tryGet(std::uint64_t page);
    /** Asks for a page; a higher priority is fetched first. Renewing a request updates its
     *  priority. No-op for resident or failed pages. */
    void request(std::uint64_t page, float priority);
    PageState state(std::uint64_t page) const;
    /** Cancels queued requests that this frame did not renew. */
    void endFrame();
    /** Installs at most maxCompletions finished reads; returns how many were installed. */
    std::size_t pump(std::size_t maxCompletions);
    /** Blocks until nothing is queued or in flight (tests, --sync mode), then pumps all. */
    void drain();

    const PageCacheStats& stats() const noexcept;
    std::uint64_t budgetBytes() const noexcept;
    /** Changes the budget (evicting as needed, never pages used by the current frame). */
    void setBudget(std::uint64_t bytes);

private:
    struct Impl;
    explicit PageCache(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> mImpl;
};

} // namespace ff::cache
