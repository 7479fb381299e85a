#pragma once

#include <ff/cache/PageCache.h>
#include <ff/runtime/CachedPageAccess.h>
#include <ff/storage/SceneFile.h>
#include <ff/storage/Status.h>

#include <cstdint>
#include <memory>

namespace ff::viewer {

/** A scene's pages streamed through a PageCache, ready for a FrameRenderer. */
struct StreamingPages {
    std::unique_ptr<cache::PageCache> cache;
    std::unique_ptr<runtime::CachedPageAccess> access;
};

/**
 * Creates the cache over `source` and makes the minimum working set resident: the root node's
 * page, without which no frame can draw anything. (One I/O thread and a maxInFlight that never
 * refuses make the order of reads, and so a --sync replay, deterministic.) Errors: OutOfBudget when the budget cannot
 * hold it (the message names --cache-mb), and whatever creating the cache reports.
 */
[[nodiscard]] Result<StreamingPages> openStreaming(
        const storage::SceneFile& scene,
        std::shared_ptr<cache::IPageSource> source,
        std::uint64_t budgetBytes,
        unsigned ioThreads,
        std::uint32_t maxInFlight = cache::PageCacheOptions{}.maxInFlight);

} // namespace ff::viewer
