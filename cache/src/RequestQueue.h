#pragma once

// The page cache's queue of requests not yet started: highest priority first, first come first
// served among equal priorities, with O(log n) renewal (priority change) and removal, so that the
// main thread can renew and cancel while I/O threads pop. Not thread-safe: PageCache guards it
// with its mutex.

#include <ff/storage/Assert.h>

#include <cstdint>
#include <optional>
#include <set>
#include <unordered_map>
#include <utility>
#include <vector>

namespace ff::cache {

class RequestQueue {
public:
    bool empty() const noexcept { return mOrder.empty(); }
    std::size_t size() const noexcept { return mOrder.size(); }
    bool contains(std::uint64_t page) const { return mItems.count(page) != 0; }

    /** Queues `page` (not queued yet) with `priority`, renewed in frame `frame`. */
    void push(std::uint64_t page, float priority, std::uint64_t frame) {
        const Key key{priority, mNextSequence++, page};
        const bool inserted = mItems.emplace(page, Item{key, frame}).second;
        FF_ASSERT(inserted);
        mOrder.insert(key);
    }

    /** Renews a queued page: new priority, renewed in `frame`. False if `page` is not queued
     *  (never was, or already taken by an I/O thread). Keeps its place among equal priorities. */
    bool renew(std::uint64_t page, float priority, std::uint64_t frame) {
        const auto it = mItems.find(page);
        if (it == mItems.end())
            return false;
        it->second.renewedFrame = frame;
        if (it->second.key.priority != priority) {
            mOrder.erase(it->second.key);
            it->second.key.priority = priority;
            mOrder.insert(it->second.key);
        }
        return true;
    }

    /** Removes and returns the highest-priority page. */
    std::optional<std::uint64_t> popHighest() {
        if (mOrder.empty())
            return std::nullopt;
        const Key key = *mOrder.begin();
        mOrder.erase(mOrder.begin());
        mItems.erase(key.page);
        return key.page;
    }

    /** The lowest-priority queued page and its priority (the one to displace first). */
    std::optional<std::pair<std::uint64_t, float>> lowest() const {
        if (mOrder.empty())
            return std::nullopt;
        const Key& key = *mOrder.rbegin();
        return std::pair{key.page, key.priority};
    }

    void erase(std::uint64_t page) {
        const auto it = mItems.find(page);
        if (it == mItems.end())
            return;
        mOrder.erase(it->second.key);
        mItems.erase(it);
    }

    /** Removes every page not renewed in `frame`, appending them to `removed`. */
    void removeNotRenewedIn(std::uint64_t frame, std::vector<std::uint64_t>& removed) {
        for (auto it = mItems.begin(); it != mItems.end();) {
            if (it->second.renewedFrame == frame) {
                ++it;
                continue;
            }
            removed.push_back(it->first);
            mOrder.erase(it->second.key);
            it = mItems.erase(it);
        }
    }

    void clear() {
        mOrder.clear();
        mItems.clear();
    }

private:
    struct Key {
        float priority;
        std::uint64_t sequence; ///< arrival order: ties are served first come, first served
        std::uint64_t page;

        bool operator<(const Key& other) const noexcept {
            if (priority != other.priority)
                return priority > other.priority; // highest first
            return sequence < other.sequence;
        }
    };
    struct Item {
        Key key;
        std::uint64_t renewedFrame;
    };

    std::set<Key> mOrder;
    std::unordered_map<std::uint64_t, Item> mItems;
    std::uint64_t mNextSequence = 0;
};

} // namespace ff::cache
