#pragma once

#include <cstdint>
#include <list>
#include <optional>
#include <unordered_map>

namespace ff::cache {

/**
 * Least-recently-used order over page numbers: touch, erase and oldest are O(1). The eviction
 * order behind every byte budget in farfield (GPU page arena, and the page cache).
 * Not thread-safe: owned by one thread.
 */
class PageLru {
public:
    /** Makes `page` the most recently used, inserting it if absent. */
    void touch(std::uint64_t page);
    bool contains(std::uint64_t page) const { return mPositions.count(page) != 0; }
    /** Removes `page` if present. */
    void erase(std::uint64_t page);
    /** The least recently used page, if any. */
    std::optional<std::uint64_t> oldest() const;
    /** The least recently used page for which `skip` returns false, if any. */
    template <typename Predicate> std::optional<std::uint64_t> oldestWhereNot(Predicate skip) const {
        for (auto it = mOrder.rbegin(); it != mOrder.rend(); ++it)
            if (!skip(*it))
                return *it;
        return std::nullopt;
    }
    std::size_t size() const { return mOrder.size(); }
    void clear();

private:
    std::list<std::uint64_t> mOrder; ///< front = most recent
    std::unordered_map<std::uint64_t, std::list<std::uint64_t>::iterator> mPositions;
};

} // namespace ff::cache
