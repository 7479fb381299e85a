#include <ff/cache/PageLru.h>

namespace ff::cache {

void PageLru::touch(std::uint64_t page) {
    const auto it = mPositions.find(page);
    if (it != mPositions.end()) {
        mOrder.splice(mOrder.begin(), mOrder, it->second);
        return;
    }
    mOrder.push_front(page);
    mPositions.emplace(page, mOrder.begin());
}

void PageLru::erase(std::uint64_t page) {
    const auto it = mPositions.find(page);
    if (it == mPositions.end())
        return;
    mOrder.erase(it->second);
    mPositions.erase(it);
}

std::optional<std::uint64_t> PageLru::oldest() const {
    if (mOrder.empty())
        return std::nullopt;
    return mOrder.back();
}

void PageLru::clear() {
    mOrder.clear();
    mPositions.clear();
}

} // namespace ff::cache
