#include <ff/runtime/PageAccess.h>

namespace ff::runtime {

PageLookup MappedPageAccess::lookup(std::uint64_t page, storage::PageType type, float /*priority*/) {
    if (const auto it = mFailures.find(failureKey(page, type)); it != mFailures.end())
        return {PageAvailability::Failed, {}, &it->second};
    Result<std::span<const std::byte>> payload = mScene.pagePayload(page, type);
    if (payload)
        return {PageAvailability::Ready, *payload, nullptr};
    const auto [it, inserted] = mFailures.emplace(failureKey(page, type), payload.status());
    return {PageAvailability::Failed, {}, &it->second};
}

} // namespace ff::runtime
