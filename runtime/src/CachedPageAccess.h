#pragma once

// Page access, frame layer over the resident layer: IPageAccess through the PageCache.

#include <ff/cache/PageCache.h>
#include <ff/runtime/PageAccess.h>

#include <cstdint>
#include <unordered_map>

namespace ff::runtime {

/** Distinct pages one frame used (found Ready), by type: the frame's working set. */
struct FramePageUse {
    std::uint64_t nodePages = 0;
    std::uint64_t geometryPages = 0;
};

/**
 * Pages through the streaming PageCache: Ready only when resident, otherwise requested with the
 * caller's priority. A frame is bracketed by beginFrame()/endFrame() (endFrame cancels requests
 * the frame no longer wanted); installing finished reads is the caller's pump(), once per frame,
 * under an upload budget. Main thread only.
 */
class CachedPageAccess final : public IPageAccess {
public:
    explicit CachedPageAccess(cache::PageCache& cache);

    void beginFrame() override;
    [[nodiscard]] PageLookup lookup(std::uint64_t page, storage::PageType type, float priority) override;
    void endFrame() override;

    cache::PageCache& cache() noexcept { return mCache; }
    /** Pages the current (or, after endFrame(), the last) frame found Ready, counted once each;
     *  everything looked up between beginFrame() and endFrame() counts, prefetch included. */
    const FramePageUse& framePageUse() const noexcept { return mFrameUse; }

private:
    cache::PageCache& mCache;
    std::unordered_map<std::uint64_t, Status> mFailures;
    FramePageUse mFrameUse;
};

} // namespace ff::runtime
