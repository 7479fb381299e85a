#include "StreamingPages.h"

#include <string>

namespace ff::viewer {

Result<StreamingPages> openStreaming(
        const storage::SceneFile& scene,
        std::shared_ptr<cache::IPageSource> source,
        std::uint64_t budgetBytes,
        unsigned ioThreads,
        std::uint32_t maxInFlight) {
    const auto rootTooLarge = [&] {
        return Status(ErrorCode::OutOfBudget, "--cache-mb " + std::to_string(budgetBytes >> 20) +
                                                      " cannot hold the scene's root page (" +
                                                      std::to_string(scene.pageSize() >> 10) + " KiB)");
    };
    if (budgetBytes < scene.pageSize())
        return rootTooLarge();
    cache::PageCacheOptions options;
    options.budgetBytes = budgetBytes;
    options.ioThreads = ioThreads;
    options.maxInFlight = maxInFlight;
    // A frame that needs more than the budget keeps the cut it has instead of reading pages it
    // can only drop (docs/methods.md, "At the budget's edge").
    options.readOnlyWhatFits = true;
    StreamingPages pages;
    FF_ASSIGN_OR_RETURN(pages.cache, cache::PageCache::create(std::move(source), options));
    const std::uint64_t rootPage = scene.header().root.page;
    pages.cache->request(rootPage, 1e30f);
    pages.cache->drain();
    if (pages.cache->state(rootPage) == cache::PageState::Failed)
        return pages.cache->failure(rootPage).value_or(Status(ErrorCode::IoError, "the root page is unreadable"));
    if (pages.cache->state(rootPage) != cache::PageState::Resident)
        return rootTooLarge();
    pages.access = std::make_unique<runtime::CachedPageAccess>(*pages.cache, scene.pageSize());
    return pages;
}

} // namespace ff::viewer
