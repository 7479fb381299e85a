#include "CachedPageAccess.h"

#include <cstring>

namespace ff::runtime {

CachedPageAccess::CachedPageAccess(cache::PageCache& cache)
    : mCache(cache) {}

void CachedPageAccess::beginFrame() {
    mCache.beginFrame();
    mFrameUse = {};
}

void CachedPageAccess::endFrame() { mCache.endFrame(); }

PageLookup CachedPageAccess::lookup(std::uint64_t page, storage::PageType type, float priority) {
    if (const auto it = mFailures.find(failureKey(page, type)); it != mFailures.end())
        return {PageAvailability::Failed, {}, &it->second};
    bool firstUse = false;
    if (const auto bytes = mCache.tryGet(page, &firstUse)) {
        // The cache verified the checksum and the page's own index; the type is ours to check.
        // A page as kept ends with its trailer, decoded or not (a decoder keeps it there).
        FF_ASSERT(bytes->size() >= sizeof(storage::PageTrailer));
        const std::size_t payloadBytes = bytes->size() - sizeof(storage::PageTrailer);
        storage::PageTrailer trailer{};
        std::memcpy(&trailer, bytes->data() + payloadBytes, sizeof(trailer));
        if (trailer.pageType != static_cast<std::uint16_t>(type)) {
            const auto [it, inserted] = mFailures.emplace(
                    failureKey(page, type), Status(ErrorCode::Corrupt, "page " + std::to_string(page) + ": page type " +
                                                             std::to_string(trailer.pageType) + ", expected " +
                                                             std::to_string(static_cast<int>(type))));
            return {PageAvailability::Failed, {}, &it->second};
        }
        if (firstUse && type == storage::PageType::Nodes)
            ++mFrameUse.nodePages;
        else if (firstUse && type == storage::PageType::Geometry)
            ++mFrameUse.geometryPages;
        return {PageAvailability::Ready, bytes->first(payloadBytes), nullptr};
    }
    if (mCache.state(page) == cache::PageState::Failed) {
        const auto [it, inserted] = mFailures.emplace(failureKey(page, type), mCache.failure(page).value_or(
                Status(ErrorCode::IoError, "page " + std::to_string(page) + ": unreadable")));
        return {PageAvailability::Failed, {}, &it->second};
    }
    mCache.request(page, priority);
    return {PageAvailability::Pending, {}, nullptr};
}

} // namespace ff::runtime
