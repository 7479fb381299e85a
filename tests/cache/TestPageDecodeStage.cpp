// The cache's decode stage: pages become what a decoder makes of them on the worker threads,
// the budget counts the decoded bytes, and a page that fails to decode fails like a bad read.

#include "FakePageSource.h"

#include <ff/cache/PageCache.h>
#include <ff/cache/PageDecoder.h>

#include <gtest/gtest.h>

#include <cstring>
#include <mutex>
#include <random>
#include <set>
#include <thread>
#include <vector>

namespace ff::cache {
namespace {

using test::FakePageSource;
using test::holdsPage;

constexpr std::uint32_t kPageSize = 256;
constexpr std::uint64_t kPageCount = 64;

/** What page `page` decodes to: its size varies with the page (half a page to twice one). */
std::size_t decodedSize(std::uint64_t page) {
    return kPageSize / 2 + (page % 4) * (kPageSize / 2);
}

std::byte decodedByte(std::uint64_t page, std::size_t k) {
    return static_cast<std::byte>((page * 29 + k * 13 + 1) & 0xff);
}

bool holdsDecoded(std::span<const std::byte> bytes, std::uint64_t page) {
    if (bytes.size() != decodedSize(page))
        return false;
    for (std::size_t k = 0; k < bytes.size(); ++k) {
        if (bytes[k] != decodedByte(page, k))
            return false;
    }
    return true;
}

/** Checks that the bytes it is given are page `index` as read, then makes them decodedSize()
 *  bytes of a pattern of its own; fails the pages it is told to, and records its threads. */
class PatternDecoder final : public IPageDecoder {
public:
    std::size_t maxDecodedBytes(std::uint32_t pageSize) const override {
        return 2 * std::size_t{pageSize};
    }

    Status decode(std::uint64_t index, PageBuffer& page) override {
        {
            std::lock_guard lock(mMutex);
            mThreads.insert(std::this_thread::get_id());
            if (!holdsPage(page.view(), index))
                ++mWrongInputs;
            if (mFailing.count(index) != 0)
                return {ErrorCode::Corrupt, "page " + std::to_string(index) + ": cannot decode"};
            if (mOversized.count(index) != 0) {
                page = {std::make_unique<std::byte[]>(3 * kPageSize), 3 * kPageSize};
                return Status::ok();
            }
        }
        const std::size_t size = decodedSize(index);
        PageBuffer decoded{std::make_unique<std::byte[]>(size), size};
        for (std::size_t k = 0; k < size; ++k)
            decoded.bytes[k] = decodedByte(index, k);
        page = std::move(decoded);
        return Status::ok();
    }

    void fail(std::uint64_t page) {
        std::lock_guard lock(mMutex);
        mFailing.insert(page);
    }
    void oversize(std::uint64_t page) {
        std::lock_guard lock(mMutex);
        mOversized.insert(page);
    }
    std::set<std::thread::id> threads() const {
        std::lock_guard lock(mMutex);
        return mThreads;
    }
    int wrongInputs() const {
        std::lock_guard lock(mMutex);
        return mWrongInputs;
    }

private:
    mutable std::mutex mMutex;
    std::set<std::uint64_t> mFailing;
    std::set<std::uint64_t> mOversized;
    std::set<std::thread::id> mThreads;
    int mWrongInputs = 0;
};

class PageDecodeStageTest : public ::testing::Test {
protected:
    std::unique_ptr<PageCache> makeCache(std::uint64_t budgetBytes) {
        PageCacheOptions options;
        options.budgetBytes = budgetBytes;
        options.ioThreads = 2;
        options.hysteresis = 0.0;
        options.decoder = mDecoder;
        auto cache = PageCache::create(mSource, options);
        EXPECT_TRUE(cache.isOk()) << cache.status().toString();
        return cache.isOk() ? std::move(cache).value() : nullptr;
    }

    void load(PageCache& cache, const std::vector<std::uint64_t>& pages) {
        cache.beginFrame();
        for (const std::uint64_t page : pages)
            cache.request(page, 1.0f);
        cache.endFrame();
        cache.drain();
    }

    /** The decoded sizes of the pages state() calls Resident. */
    std::uint64_t residentDecodedBytes(const PageCache& cache) const {
        std::uint64_t bytes = 0;
        for (std::uint64_t page = 0; page < kPageCount; ++page) {
            if (cache.state(page) == PageState::Resident)
                bytes += decodedSize(page);
        }
        return bytes;
    }

    std::shared_ptr<FakePageSource> mSource =
            std::make_shared<FakePageSource>(kPageSize, kPageCount);
    std::shared_ptr<PatternDecoder> mDecoder = std::make_shared<PatternDecoder>();
};

TEST_F(PageDecodeStageTest, TryGetHandsOutTheDecodedBytesAndTheBudgetCountsThem) {
    auto cache = makeCache(64 * kPageSize);
    ASSERT_NE(cache, nullptr);
    load(*cache, {0, 1, 2, 3, 4, 5, 6, 7});
    cache->beginFrame();
    for (std::uint64_t page = 0; page < 8; ++page) {
        const auto bytes = cache->tryGet(page);
        ASSERT_TRUE(bytes.has_value()) << page;
        EXPECT_TRUE(holdsDecoded(*bytes, page)) << page;
    }
    std::uint64_t expected = 0;
    for (std::uint64_t page = 0; page < 8; ++page)
        expected += decodedSize(page);
    EXPECT_EQ(cache->stats().residentBytes, expected);
    EXPECT_EQ(cache->stats().bytesDecoded, expected);
    EXPECT_EQ(cache->stats().bytesRead, 8u * kPageSize);
    EXPECT_EQ(mDecoder->wrongInputs(), 0); // the decoder is given each page as read
}

TEST_F(PageDecodeStageTest, DecodingRunsOnTheWorkerThreadsNeverOnTheMainThread) {
    auto cache = makeCache(64 * kPageSize);
    ASSERT_NE(cache, nullptr);
    load(*cache, {0, 1, 2, 3, 4, 5, 6, 7, 8, 9});
    const std::set<std::thread::id> threads = mDecoder->threads();
    ASSERT_FALSE(threads.empty());
    EXPECT_EQ(threads.count(std::this_thread::get_id()), 0u);
    EXPECT_LE(threads.size(), 2u);
}

TEST_F(PageDecodeStageTest, PagesOfEverySizeStayWithinTheBudgetThroughEviction) {
    // Room for about five average pages: every frame evicts, with sizes from 0.5 to 2 pages.
    const std::uint64_t budget = 6 * kPageSize;
    auto cache = makeCache(budget);
    ASSERT_NE(cache, nullptr);
    std::mt19937 random(7);
    for (int frame = 0; frame < 200; ++frame) {
        std::vector<std::uint64_t> wanted;
        const int count = 1 + static_cast<int>(random() % 3);
        for (int i = 0; i < count; ++i)
            wanted.push_back(random() % kPageCount);
        load(*cache, wanted);
        ASSERT_LE(cache->stats().residentBytes, budget) << "frame " << frame;
        ASSERT_EQ(cache->stats().residentBytes, residentDecodedBytes(*cache)) << "frame " << frame;
        cache->beginFrame();
        for (const std::uint64_t page : wanted) {
            // What fits is resident and decoded; three twice-a-page pages may not all fit.
            if (const auto bytes = cache->tryGet(page)) {
                ASSERT_TRUE(holdsDecoded(*bytes, page)) << "frame " << frame << " page " << page;
            }
        }
        cache->endFrame();
    }
    EXPECT_GT(cache->stats().evicted, 0u);
}

TEST_F(PageDecodeStageTest, APageThatFailsToDecodeFailsWithTheDecodersStatusAndIsNotReadAgain) {
    mDecoder->fail(5);
    auto cache = makeCache(64 * kPageSize);
    ASSERT_NE(cache, nullptr);
    load(*cache, {4, 5, 6});
    EXPECT_EQ(cache->state(4), PageState::Resident);
    EXPECT_EQ(cache->state(6), PageState::Resident);
    ASSERT_EQ(cache->state(5), PageState::Failed);
    EXPECT_EQ(cache->failure(5)->message(), "page 5: cannot decode");
    EXPECT_EQ(cache->stats().failed, 1u);
    load(*cache, {5});
    EXPECT_EQ(mSource->readCount(5), 1u);
    EXPECT_EQ(cache->stats().residentBytes, decodedSize(4) + decodedSize(6));
}

TEST_F(PageDecodeStageTest, ADecoderBreakingItsSizePromiseFailsThePageRatherThanTheBudget) {
    mDecoder->oversize(3);
    auto cache = makeCache(64 * kPageSize);
    ASSERT_NE(cache, nullptr);
    load(*cache, {3});
    ASSERT_EQ(cache->state(3), PageState::Failed);
    EXPECT_EQ(cache->failure(3)->code(), ErrorCode::Internal);
    EXPECT_EQ(cache->stats().residentBytes, 0u);
}

TEST_F(PageDecodeStageTest, TheBudgetMustHoldOneDecodedPage) {
    PageCacheOptions options;
    options.budgetBytes = kPageSize; // one page as read, half the decoder's largest
    options.decoder = mDecoder;
    const auto cache = PageCache::create(mSource, options);
    ASSERT_FALSE(cache.isOk());
    EXPECT_EQ(cache.status().code(), ErrorCode::InvalidArgument);
    EXPECT_NE(cache.status().message().find("512 bytes decoded"), std::string::npos)
            << cache.status().message();
    options.budgetBytes = 2 * kPageSize;
    const auto fits = PageCache::create(mSource, options);
    ASSERT_TRUE(fits.isOk()) << fits.status().toString();
    EXPECT_EQ((*fits)->maxPageBytes(), 2u * kPageSize);
}

TEST_F(PageDecodeStageTest, ADecoderThatKeepsPagesAsReadChangesNothing) {
    class Keep final : public IPageDecoder {
    public:
        std::size_t maxDecodedBytes(std::uint32_t pageSize) const override { return pageSize; }
        Status decode(std::uint64_t, PageBuffer&) override { return Status::ok(); }
    };
    PageCacheOptions options;
    options.budgetBytes = 8 * kPageSize;
    options.decoder = std::make_shared<Keep>();
    auto cache = PageCache::create(mSource, options);
    ASSERT_TRUE(cache.isOk());
    load(**cache, {1, 2});
    (*cache)->beginFrame();
    const auto bytes = (*cache)->tryGet(2);
    ASSERT_TRUE(bytes.has_value());
    EXPECT_TRUE(holdsPage(*bytes, 2));
    EXPECT_EQ(bytes->size(), kPageSize);
    EXPECT_EQ((*cache)->stats().residentBytes, 2u * kPageSize);
}

} // namespace
} // namespace ff::cache
