#pragma once

// An in-memory IPageSource for the page cache tests: page i holds pageByte(i, k) at offset k,
// chosen pages fail, and a gate holds reads in flight until the test opens it, so tests decide
// deterministically what is being read when (no sleeps).

#include <ff/cache/PageCache.h>

#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <map>
#include <mutex>
#include <set>
#include <span>
#include <string>
#include <vector>

namespace ff::cache::test {

inline std::byte pageByte(std::uint64_t page, std::size_t offset) {
    return static_cast<std::byte>((page * 131 + offset * 7 + 3) & 0xff);
}

/** True if `bytes` are page `page`'s bytes. */
inline bool holdsPage(std::span<const std::byte> bytes, std::uint64_t page) {
    for (std::size_t k = 0; k < bytes.size(); ++k) {
        if (bytes[k] != pageByte(page, k))
            return false;
    }
    return true;
}

class FakePageSource final : public IPageSource {
public:
    FakePageSource(std::uint32_t pageSize, std::uint64_t pageCount)
        : mPageSize(pageSize)
        , mPageCount(pageCount) {}

    std::uint32_t pageSize() const override { return mPageSize; }
    std::uint64_t pageCount() const override { return mPageCount; }

    Status readPage(std::uint64_t index, std::span<std::byte> out) override {
        bool fail = false;
        {
            std::unique_lock lock(mMutex);
            ++mWaiting;
            mChanged.notify_all();
            mChanged.wait(lock, [this] { return mGateOpen || mPermits > 0; });
            if (!mGateOpen)
                --mPermits;
            --mWaiting;
            mReadOrder.push_back(index);
            ++mReadCounts[index];
            fail = mFailing.count(index) != 0;
        }
        if (fail)
            return {ErrorCode::IoError, "page " + std::to_string(index) + ": injected failure"};
        for (std::size_t k = 0; k < out.size(); ++k)
            out[k] = pageByte(index, k);
        {
            std::lock_guard lock(mMutex);
            ++mFinished;
        }
        mChanged.notify_all();
        return Status::ok();
    }

    /** Reads block in readPage() until openGate() (or a permit from allow()). */
    void closeGate() {
        std::lock_guard lock(mMutex);
        mGateOpen = false;
    }
    void openGate() {
        {
            std::lock_guard lock(mMutex);
            mGateOpen = true;
        }
        mChanged.notify_all();
    }
    /** Lets `count` more reads through a closed gate. */
    void allow(unsigned count) {
        {
            std::lock_guard lock(mMutex);
            mPermits += count;
        }
        mChanged.notify_all();
    }
    /** Blocks until `count` reads wait at the closed gate. */
    void waitUntilBlocked(unsigned count) {
        std::unique_lock lock(mMutex);
        mChanged.wait(lock, [this, count] { return mWaiting >= count; });
    }
    /** Blocks until `count` reads have passed the gate and finished (successful ones). */
    void waitUntilFinished(std::size_t count) {
        std::unique_lock lock(mMutex);
        mChanged.wait(lock, [this, count] { return mFinished >= count; });
    }

    void failPage(std::uint64_t page) {
        std::lock_guard lock(mMutex);
        mFailing.insert(page);
    }

    /** Pages in the order reads passed the gate. */
    std::vector<std::uint64_t> readOrder() const {
        std::lock_guard lock(mMutex);
        return mReadOrder;
    }
    unsigned readCount(std::uint64_t page) const {
        std::lock_guard lock(mMutex);
        const auto it = mReadCounts.find(page);
        return it == mReadCounts.end() ? 0 : it->second;
    }

private:
    const std::uint32_t mPageSize;
    const std::uint64_t mPageCount;
    mutable std::mutex mMutex;
    std::condition_variable mChanged;
    bool mGateOpen = true;
    unsigned mPermits = 0;
    unsigned mWaiting = 0;
    std::size_t mFinished = 0;
    std::set<std::uint64_t> mFailing;
    std::vector<std::uint64_t> mReadOrder;
    std::map<std::uint64_t, unsigned> mReadCounts;
};

} // namespace ff::cache::test
