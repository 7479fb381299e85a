#include "FakePageSource.h"

#include <ff/cache/PageCache.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <numeric>
#include <random>
#include <set>
#include <thread>
#include <vector>

namespace ff::cache {
namespace {

using test::FakePageSource;
using test::holdsPage;

constexpr std::uint32_t kPageSize = 256;

PageCacheOptions makeOptions(
        std::uint64_t budgetBytes,
        unsigned ioThreads = 2,
        std::uint32_t maxInFlight = 64,
        double hysteresis = 0.0) {
    PageCacheOptions options;
    options.budgetBytes = budgetBytes;
    options.ioThreads = ioThreads;
    options.maxInFlight = maxInFlight;
    options.hysteresis = hysteresis;
    return options;
}

std::unique_ptr<PageCache>
makeCache(const std::shared_ptr<FakePageSource>& source, const PageCacheOptions& options) {
    auto cache = PageCache::create(source, options);
    EXPECT_TRUE(cache.isOk()) << cache.status().toString();
    return cache.isOk() ? std::move(cache).value() : nullptr;
}

/** One frame that requests `pages` and waits for them. */
void loadPages(PageCache& cache, const std::vector<std::uint64_t>& pages) {
    cache.beginFrame();
    for (const std::uint64_t page : pages)
        cache.request(page, 1.0f);
    cache.endFrame();
    cache.drain();
}

std::vector<std::uint64_t> range(std::uint64_t first, std::uint64_t end) {
    std::vector<std::uint64_t> pages(end - first);
    std::iota(pages.begin(), pages.end(), first);
    return pages;
}

::testing::AssertionResult withinBudget(const PageCache& cache) {
    const PageCacheStats& s = cache.stats();
    if (s.residentBytes <= cache.budgetBytes())
        return ::testing::AssertionSuccess();
    return ::testing::AssertionFailure()
           << "residentBytes " << s.residentBytes << " > budget " << cache.budgetBytes();
}

/** residentBytes agrees with the pages state() calls Resident. */
::testing::AssertionResult residentBytesConsistent(const PageCache& cache, std::uint64_t pages) {
    std::uint64_t resident = 0;
    for (std::uint64_t page = 0; page < pages; ++page) {
        if (cache.state(page) == PageState::Resident)
            resident += kPageSize;
    }
    if (resident == cache.stats().residentBytes)
        return ::testing::AssertionSuccess();
    return ::testing::AssertionFailure()
           << "state() says " << resident << " resident bytes, stats say "
           << cache.stats().residentBytes;
}

/** The spans tryGet() returned this frame, with the page each must still hold. */
struct HeldSpans {
    std::vector<std::pair<std::uint64_t, std::span<const std::byte>>> spans;

    ::testing::AssertionResult intact() const {
        for (const auto& [page, bytes] : spans) {
            if (bytes.size() != kPageSize || !holdsPage(bytes, page))
                return ::testing::AssertionFailure() << "span of page " << page << " changed";
        }
        return ::testing::AssertionSuccess();
    }
};

// ---- creation ---------------------------------------------------------------------------

TEST(PageCacheTest, TryGetTellsWhetherItIsTheFramesFirstUseOfAPage) {
    auto source = std::make_shared<FakePageSource>(kPageSize, 4);
    auto cache = makeCache(source, makeOptions(4 * kPageSize));
    ASSERT_NE(cache, nullptr);
    loadPages(*cache, {1, 2});
    for (int frame = 0; frame < 2; ++frame) {
        cache->beginFrame();
        bool firstUse = false;
        ASSERT_TRUE(cache->tryGet(1, &firstUse).has_value());
        EXPECT_TRUE(firstUse) << "frame " << frame;
        ASSERT_TRUE(cache->tryGet(1, &firstUse).has_value());
        EXPECT_FALSE(firstUse) << "frame " << frame;
        ASSERT_TRUE(cache->tryGet(2, &firstUse).has_value());
        EXPECT_TRUE(firstUse) << "frame " << frame;
        firstUse = true;
        EXPECT_FALSE(cache->tryGet(3, &firstUse).has_value());
        EXPECT_TRUE(firstUse) << "left alone for a page that is not resident";
        cache->endFrame();
    }
}

TEST(PageCacheTest, RefusesABudgetBelowOnePage) {
    auto source = std::make_shared<FakePageSource>(kPageSize, 10);
    const auto refused = PageCache::create(source, makeOptions(kPageSize - 1));
    ASSERT_FALSE(refused.isOk());
    EXPECT_EQ(refused.status().code(), ErrorCode::InvalidArgument);
    EXPECT_NE(refused.status().message().find("cannot hold one page"), std::string::npos)
            << refused.status().message();

    EXPECT_TRUE(PageCache::create(source, makeOptions(kPageSize)).isOk());
}

TEST(PageCacheTest, RefusesImpossibleOptions) {
    auto source = std::make_shared<FakePageSource>(kPageSize, 10);
    for (const PageCacheOptions& options :
         {makeOptions(4 * kPageSize, 0),
          makeOptions(4 * kPageSize, 1, 0),
          makeOptions(4 * kPageSize, 1, 8, 1.0),
          makeOptions(4 * kPageSize, 1, 8, -0.1)}) {
        const auto cache = PageCache::create(source, options);
        ASSERT_FALSE(cache.isOk());
        EXPECT_EQ(cache.status().code(), ErrorCode::InvalidArgument);
    }
}

// ---- basic streaming ----------------------------------------------------------------------

TEST(PageCacheTest, DrainInstallsEverythingRequested) {
    auto source = std::make_shared<FakePageSource>(kPageSize, 50);
    auto cache = makeCache(source, makeOptions(64 * kPageSize));
    cache->beginFrame();
    for (std::uint64_t page = 0; page < 50; ++page) {
        EXPECT_FALSE(cache->tryGet(page).has_value());
        cache->request(page, static_cast<float>(page % 7));
        EXPECT_EQ(cache->state(page), PageState::Pending);
    }
    cache->endFrame();
    cache->drain();

    const PageCacheStats& s = cache->stats();
    EXPECT_EQ(s.requests, 50u);
    EXPECT_EQ(s.completed, 50u);
    EXPECT_EQ(s.inFlight, 0u);
    EXPECT_EQ(s.misses, 50u);
    EXPECT_EQ(s.bytesRead, 50u * kPageSize);
    EXPECT_EQ(s.residentBytes, 50u * kPageSize);
    EXPECT_EQ(s.peakResidentBytes, 50u * kPageSize);
    cache->beginFrame();
    for (std::uint64_t page = 0; page < 50; ++page) {
        EXPECT_EQ(cache->state(page), PageState::Resident);
        const auto bytes = cache->tryGet(page);
        ASSERT_TRUE(bytes.has_value());
        EXPECT_TRUE(holdsPage(*bytes, page)) << page;
    }
    EXPECT_EQ(cache->stats().hits, 50u);
    // Requests for resident pages are no-ops.
    cache->request(3, 9.0f);
    EXPECT_EQ(cache->stats().requests, 50u);
    EXPECT_EQ(source->readCount(3), 1u);
}

TEST(PageCacheTest, FetchToResidentRunsFromTheRequestToTheInstall) {
    auto source = std::make_shared<FakePageSource>(kPageSize, 10);
    auto cache = makeCache(source, makeOptions(16 * kPageSize));
    cache->beginFrame();
    for (std::uint64_t page = 0; page < 4; ++page)
        cache->request(page, 1.0f);
    source->waitUntilFinished(4);
    // Read long ago, installed only now: the frame saw the page when pump() made it resident.
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    cache->drain();
    const LatencyHistogram& latency = cache->stats().fetchToResident;
    EXPECT_EQ(latency.count(), 4u);
    EXPECT_GE(latency.quantile(0.0), 0.05);
    // Resident pages asked for again are no new fetch.
    loadPages(*cache, range(0, 4));
    EXPECT_EQ(cache->stats().fetchToResident.count(), 4u);
}

TEST(PageCacheTest, PumpInstallsAtMostTheGivenNumber) {
    auto source = std::make_shared<FakePageSource>(kPageSize, 10);
    auto cache = makeCache(source, makeOptions(16 * kPageSize));
    cache->beginFrame();
    for (std::uint64_t page = 0; page < 5; ++page)
        cache->request(page, 1.0f);
    source->waitUntilFinished(5);
    // The reads are done; they become resident only through pump().
    EXPECT_EQ(cache->stats().residentBytes, 0u);
    EXPECT_EQ(cache->state(0), PageState::Pending);
    // (A finished read may still be on its way to the completion queue: count, don't expect.)
    std::size_t installed = 0;
    for (int i = 0; i < 3; ++i) {
        const std::size_t now = cache->pump(2);
        EXPECT_LE(now, 2u);
        installed += now;
        EXPECT_EQ(cache->stats().residentBytes, installed * kPageSize);
    }
    cache->drain();
    EXPECT_EQ(cache->stats().residentBytes, 5u * kPageSize);
    EXPECT_EQ(cache->pump(2), 0u);
}

// ---- the budget ---------------------------------------------------------------------------

TEST(PageCacheTest, ResidentBytesNeverExceedTheBudgetUnderRandomSequences) {
    constexpr std::uint64_t kPages = 60;
    constexpr std::uint32_t kMaxInFlight = 8;
    for (const std::uint32_t seed : {1u, 2u, 3u}) {
        SCOPED_TRACE(seed);
        std::mt19937 rng(seed);
        auto source = std::make_shared<FakePageSource>(kPageSize, kPages);
        // Not a whole number of pages, with hysteresis: the edges of the eviction arithmetic.
        auto cache = makeCache(source, makeOptions(10 * kPageSize + 100, 2, kMaxInFlight, 0.2));
        HeldSpans held;
        std::uniform_int_distribution<std::uint64_t> pageDist(0, kPages - 1);
        std::uniform_int_distribution<int> opDist(0, 99);
        std::uniform_real_distribution<float> priorityDist(0.0f, 10.0f);
        for (int step = 0; step < 4000; ++step) {
            const int op = opDist(rng);
            if (op < 8) {
                ASSERT_TRUE(held.intact());
                held.spans.clear();
                cache->beginFrame();
            } else if (op < 40) {
                const std::uint64_t page = pageDist(rng);
                if (const auto bytes = cache->tryGet(page)) {
                    ASSERT_TRUE(holdsPage(*bytes, page));
                    held.spans.emplace_back(page, *bytes);
                }
            } else if (op < 75) {
                cache->request(pageDist(rng), priorityDist(rng));
            } else if (op < 83) {
                cache->endFrame();
            } else if (op < 99) {
                cache->pump(static_cast<std::size_t>(opDist(rng) % 4));
            } else {
                cache->drain();
            }
            ASSERT_TRUE(withinBudget(*cache)) << "step " << step << " op " << op;
            ASSERT_LE(cache->stats().inFlight, kMaxInFlight);
            ASSERT_TRUE(held.intact()) << "step " << step;
        }
        cache->drain();
        EXPECT_TRUE(withinBudget(*cache));
        EXPECT_TRUE(residentBytesConsistent(*cache, kPages));
        EXPECT_GT(cache->stats().completed, 0u);
        EXPECT_GT(cache->stats().evicted, 0u);
    }
}

TEST(PageCacheTest, StaysWithinBudgetWhenTheWorkingSetExceedsIt) {
    constexpr std::uint64_t kPages = 100;
    auto source = std::make_shared<FakePageSource>(kPageSize, kPages);
    auto cache = makeCache(source, makeOptions(10 * kPageSize, 2, 128, 0.05));
    for (int frame = 0; frame < 30; ++frame) {
        cache->beginFrame();
        HeldSpans held;
        for (std::uint64_t page = 0; page < kPages; ++page) {
            if (const auto bytes = cache->tryGet(page))
                held.spans.emplace_back(page, *bytes);
            else
                cache->request(page, static_cast<float>(page));
            ASSERT_TRUE(withinBudget(*cache));
        }
        cache->endFrame();
        cache->drain();
        ASSERT_TRUE(withinBudget(*cache));
        ASSERT_TRUE(held.intact());
        ASSERT_TRUE(residentBytesConsistent(*cache, kPages));
    }
    EXPECT_GT(cache->stats().dropped, 0u);
    EXPECT_LE(cache->stats().peakResidentBytes, 10u * kPageSize);
}

TEST(PageCacheTest, AlternatingWorkingSetsReplaceEachOtherWithinBudget) {
    constexpr std::uint64_t kPages = 20;
    auto source = std::make_shared<FakePageSource>(kPageSize, kPages);
    auto cache = makeCache(source, makeOptions(10 * kPageSize, 2, 64, 0.05));
    for (int frame = 0; frame < 20; ++frame) {
        const std::uint64_t first = frame % 2 == 0 ? 0 : 10;
        cache->beginFrame();
        HeldSpans held;
        for (std::uint64_t page = first; page < first + 10; ++page) {
            if (const auto bytes = cache->tryGet(page))
                held.spans.emplace_back(page, *bytes);
            else
                cache->request(page, 1.0f);
        }
        cache->endFrame();
        cache->drain();
        ASSERT_TRUE(withinBudget(*cache));
        ASSERT_TRUE(held.intact());
        // The previous frame's set is evictable now, so the whole new set fits.
        for (std::uint64_t page = first; page < first + 10; ++page)
            EXPECT_EQ(cache->state(page), PageState::Resident) << "frame " << frame;
    }
    EXPECT_EQ(cache->stats().dropped, 0u);
}

TEST(PageCacheTest, AllPagesRequestedAtOnceStayWithinBudget) {
    constexpr std::uint64_t kPages = 200;
    auto source = std::make_shared<FakePageSource>(kPageSize, kPages);
    auto cache = makeCache(source, makeOptions(16 * kPageSize, 2, 256, 0.05));
    loadPages(*cache, range(0, kPages));
    EXPECT_TRUE(withinBudget(*cache));
    EXPECT_TRUE(residentBytesConsistent(*cache, kPages));
    // Nothing is used by the frame, so every read fits by evicting older ones.
    EXPECT_EQ(cache->stats().completed, kPages);
    EXPECT_EQ(cache->stats().dropped, 0u);
    EXPECT_EQ(
            cache->stats().evicted * kPageSize + cache->stats().residentBytes, kPages * kPageSize);
}

TEST(PageCacheTest, RequestsBeyondMaxInFlightAreRefused) {
    constexpr std::uint64_t kPages = 40;
    auto source = std::make_shared<FakePageSource>(kPageSize, kPages);
    source->closeGate();
    auto cache = makeCache(source, makeOptions(64 * kPageSize, 2, 8));
    cache->beginFrame();
    for (std::uint64_t page = 0; page < kPages; ++page)
        cache->request(page, 1.0f); // equal priorities: nothing displaces anything
    EXPECT_EQ(cache->stats().requests, 8u);
    EXPECT_EQ(cache->stats().refused, kPages - 8);
    EXPECT_EQ(cache->stats().inFlight, 8u);
    EXPECT_EQ(cache->state(8), PageState::Absent);
    cache->endFrame();
    source->openGate();
    cache->drain();
    EXPECT_EQ(cache->stats().residentBytes, 8u * kPageSize);
}

// ---- the current frame --------------------------------------------------------------------

TEST(PageCacheTest, NeverEvictsPagesUsedByTheCurrentFrame) {
    auto source = std::make_shared<FakePageSource>(kPageSize, 10);
    auto cache = makeCache(source, makeOptions(4 * kPageSize));
    loadPages(*cache, range(0, 4));

    cache->beginFrame();
    HeldSpans held;
    for (std::uint64_t page = 0; page < 4; ++page)
        held.spans.emplace_back(page, *cache->tryGet(page));
    for (std::uint64_t page = 4; page < 10; ++page)
        cache->request(page, 5.0f);
    cache->endFrame();
    cache->drain();
    // Every completion needed a page the frame uses: all dropped, back to Absent.
    EXPECT_EQ(cache->stats().dropped, 6u);
    EXPECT_EQ(cache->stats().evicted, 0u);
    for (std::uint64_t page = 4; page < 10; ++page)
        EXPECT_EQ(cache->state(page), PageState::Absent);
    EXPECT_TRUE(held.intact());
    for (const auto& [page, bytes] : held.spans)
        EXPECT_EQ(cache->tryGet(page)->data(), bytes.data()); // same memory, not a copy

    // Next frame: only page 0 is used, so the least recently used others make room.
    cache->beginFrame();
    ASSERT_TRUE(cache->tryGet(0).has_value());
    cache->request(4, 1.0f); // a dropped page can be asked for again
    cache->endFrame();
    cache->drain();
    EXPECT_EQ(cache->state(4), PageState::Resident);
    EXPECT_EQ(cache->state(0), PageState::Resident);
    EXPECT_EQ(cache->state(1), PageState::Absent); // the least recently used
    EXPECT_EQ(cache->state(2), PageState::Resident);
    EXPECT_EQ(cache->state(3), PageState::Resident);
    EXPECT_EQ(cache->stats().evicted, 1u);
    EXPECT_TRUE(withinBudget(*cache));
}

TEST(PageCacheTest, CompletionsEvictOnlyPagesTheFrameDoesNotUse) {
    auto source = std::make_shared<FakePageSource>(kPageSize, 10);
    auto cache = makeCache(source, makeOptions(4 * kPageSize, 1));
    loadPages(*cache, range(0, 4));
    cache->beginFrame();
    ASSERT_TRUE(cache->tryGet(0).has_value());
    ASSERT_TRUE(cache->tryGet(1).has_value());
    for (std::uint64_t page = 4; page < 7; ++page)
        cache->request(page, static_cast<float>(10 - page)); // read 4, 5, 6 in that order
    cache->endFrame();
    cache->drain();
    // 4 evicts 2, 5 evicts 3, 6 evicts 4: a page installed this frame is not used by it yet.
    EXPECT_EQ(cache->state(0), PageState::Resident);
    EXPECT_EQ(cache->state(1), PageState::Resident);
    EXPECT_EQ(cache->state(2), PageState::Absent);
    EXPECT_EQ(cache->state(3), PageState::Absent);
    EXPECT_EQ(cache->state(4), PageState::Absent);
    EXPECT_EQ(cache->state(5), PageState::Resident);
    EXPECT_EQ(cache->state(6), PageState::Resident);
    EXPECT_EQ(cache->stats().evicted, 3u);
    EXPECT_EQ(cache->stats().dropped, 0u);
    EXPECT_TRUE(withinBudget(*cache));
}

// ---- reading only what fits (readOnlyWhatFits) ------------------------------------------

PageCacheOptions fitting(PageCacheOptions options) {
    options.readOnlyWhatFits = true;
    return options;
}

TEST(PageCacheTest, ReadOnlyWhatFitsReadsNothingWhileTheFrameFillsTheBudget) {
    auto source = std::make_shared<FakePageSource>(kPageSize, 10);
    auto cache = makeCache(source, fitting(makeOptions(4 * kPageSize)));
    loadPages(*cache, range(0, 4));
    const std::uint64_t readBefore = cache->stats().bytesRead;
    cache->beginFrame();
    for (std::uint64_t page = 0; page < 4; ++page)
        ASSERT_TRUE(cache->tryGet(page).has_value());
    for (std::uint64_t page = 4; page < 10; ++page)
        cache->request(page, 5.0f);
    cache->endFrame();
    cache->drain();
    // The same frame with the option off reads six pages and drops them all
    // (NeverEvictsPagesUsedByTheCurrentFrame); here nothing is read.
    EXPECT_EQ(cache->stats().noRoom, 6u);
    EXPECT_EQ(cache->stats().bytesRead, readBefore);
    EXPECT_EQ(cache->stats().dropped, 0u);
    for (std::uint64_t page = 4; page < 10; ++page)
        EXPECT_EQ(cache->state(page), PageState::Absent);
}

TEST(PageCacheTest, ReadOnlyWhatFitsCountsReadsUnderWayAndThePreviousFramesPages) {
    auto source = std::make_shared<FakePageSource>(kPageSize, 20);
    source->closeGate();
    auto cache = makeCache(source, fitting(makeOptions(6 * kPageSize, 1)));
    cache->beginFrame();
    for (std::uint64_t page = 0; page < 10; ++page)
        cache->request(page, 1.0f);
    EXPECT_EQ(cache->stats().requests, 6u); // six reads under way fill the budget
    EXPECT_EQ(cache->stats().noRoom, 4u);
    // More urgent than what is queued: displaces the least urgent queued request.
    cache->request(10, 9.0f);
    EXPECT_EQ(cache->stats().requests, 7u);
    EXPECT_EQ(cache->stats().cancelled, 1u);
    EXPECT_EQ(cache->stats().noRoom, 4u);
    cache->endFrame();
    source->openGate();
    cache->drain();
    EXPECT_EQ(cache->stats().residentBytes, 6u * kPageSize);

    // A frame that used five pages: the next frame may claim only one more read, even before
    // it has used anything itself.
    cache->beginFrame();
    std::uint64_t used = 0;
    for (std::uint64_t page = 0; page <= 10 && used < 5; ++page)
        used += cache->tryGet(page).has_value() ? 1u : 0u;
    ASSERT_EQ(used, 5u);
    cache->endFrame();
    cache->beginFrame();
    cache->request(15, 1.0f);
    cache->request(16, 1.0f);
    EXPECT_EQ(cache->stats().requests, 8u);
    EXPECT_EQ(cache->stats().noRoom, 5u);
    cache->endFrame();
    cache->drain();
}

// A still camera whose frame needs 20 pages under an 8-page budget, 40 frames: with the option
// every page is read once and reading stops once the budget is full; without it the missing
// twelve are read and dropped again every frame (the thrash of issue 13).
TEST(PageCacheTest, AStillFrameNeedingMoreThanTheBudgetStopsReadingOnceItIsFull) {
    for (const bool readOnlyWhatFits : {true, false}) {
        SCOPED_TRACE(readOnlyWhatFits ? "reading only what fits" : "reading everything asked for");
        auto source = std::make_shared<FakePageSource>(kPageSize, 20);
        PageCacheOptions options = makeOptions(8 * kPageSize, 2, 64);
        options.readOnlyWhatFits = readOnlyWhatFits;
        auto cache = makeCache(source, options);
        std::uint64_t readsInTheLastHalf = 0;
        for (int frame = 0; frame < 40; ++frame) {
            const std::uint64_t before = cache->stats().bytesRead;
            cache->beginFrame();
            for (std::uint64_t page = 0; page < 20; ++page) {
                if (!cache->tryGet(page))
                    cache->request(page, static_cast<float>(20 - page));
            }
            cache->endFrame();
            cache->drain();
            ASSERT_TRUE(withinBudget(*cache));
            if (frame >= 20)
                readsInTheLastHalf += cache->stats().bytesRead - before;
        }
        const std::vector<std::uint64_t> reads = source->readOrder();
        const std::set<std::uint64_t> unique(reads.begin(), reads.end());
        if (readOnlyWhatFits) {
            EXPECT_EQ(reads.size(), unique.size()) << "a page was read twice";
            EXPECT_EQ(readsInTheLastHalf, 0u);
            EXPECT_EQ(cache->stats().residentBytes, 8u * kPageSize);
        } else {
            EXPECT_GT(reads.size(), 10 * unique.size());
            EXPECT_GT(readsInTheLastHalf, 0u);
        }
    }
}

TEST(PageCacheTest, SetBudgetShrinkingEvictsButKeepsCurrentFramePages) {
    auto source = std::make_shared<FakePageSource>(kPageSize, 10);
    auto cache = makeCache(source, makeOptions(8 * kPageSize));
    loadPages(*cache, range(0, 8));
    cache->beginFrame();
    HeldSpans held;
    for (std::uint64_t page = 0; page < 3; ++page)
        held.spans.emplace_back(page, *cache->tryGet(page));

    cache->setBudget(4 * kPageSize);
    EXPECT_EQ(cache->budgetBytes(), 4u * kPageSize);
    EXPECT_TRUE(withinBudget(*cache));
    EXPECT_EQ(cache->stats().residentBytes, 4u * kPageSize);
    for (std::uint64_t page = 0; page < 3; ++page)
        EXPECT_EQ(cache->state(page), PageState::Resident);
    EXPECT_TRUE(held.intact());

    // Below what the frame holds: the frame's pages stay until the next beginFrame().
    cache->setBudget(2 * kPageSize);
    EXPECT_EQ(cache->stats().residentBytes, 3u * kPageSize);
    EXPECT_TRUE(held.intact());
    cache->request(9, 1.0f);
    cache->endFrame();
    cache->drain();
    EXPECT_EQ(cache->state(9), PageState::Absent); // no room: dropped
    EXPECT_EQ(cache->stats().dropped, 1u);
    cache->beginFrame();
    EXPECT_TRUE(withinBudget(*cache));
    EXPECT_EQ(cache->stats().residentBytes, 2u * kPageSize);
}

// ---- priorities and cancellation ----------------------------------------------------------

TEST(PageCacheTest, ServesHigherPrioritiesFirst) {
    auto source = std::make_shared<FakePageSource>(kPageSize, 10);
    source->closeGate();
    auto cache = makeCache(source, makeOptions(16 * kPageSize, 1));
    cache->beginFrame();
    cache->request(0, 0.0f);
    source->waitUntilBlocked(1); // the only I/O thread holds page 0; the rest queue up
    const float priorities[] = {3.0f, 1.0f, 5.0f, 2.0f, 4.0f};
    for (std::uint64_t page = 1; page <= 5; ++page)
        cache->request(page, priorities[page - 1]);
    cache->request(2, 10.0f); // renewal raises page 2 above everything
    cache->request(6, 4.0f);  // equal to page 5: first asked, first read
    cache->endFrame();
    source->openGate();
    cache->drain();
    EXPECT_EQ(source->readOrder(), (std::vector<std::uint64_t>{0, 2, 3, 5, 6, 1, 4}));
    EXPECT_EQ(cache->stats().requests, 7u);
}

TEST(PageCacheTest, EndFrameCancelsRequestsNotRenewedAndKeepsRenewedOnes) {
    auto source = std::make_shared<FakePageSource>(kPageSize, 10);
    source->closeGate();
    auto cache = makeCache(source, makeOptions(16 * kPageSize, 1));
    cache->beginFrame();
    cache->request(0, 1.0f);
    source->waitUntilBlocked(1);
    for (std::uint64_t page = 1; page <= 3; ++page)
        cache->request(page, 1.0f);
    cache->endFrame(); // all renewed this frame
    EXPECT_EQ(cache->stats().cancelled, 0u);

    cache->beginFrame();
    cache->request(1, 1.0f);
    cache->request(3, 2.0f);
    cache->endFrame();
    EXPECT_EQ(cache->stats().cancelled, 1u);
    EXPECT_EQ(cache->state(2), PageState::Absent);
    EXPECT_EQ(cache->state(0), PageState::Pending); // running: not cancelled
    EXPECT_EQ(cache->stats().inFlight, 3u);

    source->openGate();
    cache->drain();
    EXPECT_EQ(source->readOrder(), (std::vector<std::uint64_t>{0, 3, 1}));
    EXPECT_EQ(cache->state(0), PageState::Resident);
    EXPECT_EQ(cache->state(1), PageState::Resident);
    EXPECT_EQ(cache->state(2), PageState::Absent);
    EXPECT_EQ(cache->state(3), PageState::Resident);
    EXPECT_EQ(source->readCount(2), 0u);

    // A cancelled page can be requested again.
    loadPages(*cache, {2});
    EXPECT_EQ(cache->state(2), PageState::Resident);
}

TEST(PageCacheTest, AFullQueueDisplacesItsLeastUrgentRequestForAMoreUrgentOne) {
    auto source = std::make_shared<FakePageSource>(kPageSize, 10);
    source->closeGate();
    auto cache = makeCache(source, makeOptions(16 * kPageSize, 1, 3));
    cache->beginFrame();
    cache->request(0, 0.0f);
    source->waitUntilBlocked(1);
    cache->request(1, 1.0f);
    cache->request(2, 5.0f);
    cache->request(3, 3.0f); // full: displaces page 1
    EXPECT_EQ(cache->state(1), PageState::Absent);
    EXPECT_EQ(cache->stats().cancelled, 1u);
    cache->request(4, 0.5f); // full, and less urgent than anything queued: refused
    EXPECT_EQ(cache->state(4), PageState::Absent);
    EXPECT_EQ(cache->stats().refused, 1u);
    cache->endFrame();
    source->openGate();
    cache->drain();
    EXPECT_EQ(source->readOrder(), (std::vector<std::uint64_t>{0, 2, 3}));
}

// ---- failures -----------------------------------------------------------------------------

TEST(PageCacheTest, AFailedPageIsCountedOnceAndNeverReadAgain) {
    auto source = std::make_shared<FakePageSource>(kPageSize, 10);
    source->failPage(3);
    auto cache = makeCache(source, makeOptions(16 * kPageSize));
    loadPages(*cache, range(0, 6));
    EXPECT_EQ(cache->state(3), PageState::Failed);
    EXPECT_EQ(cache->stats().failed, 1u);
    const auto failure = cache->failure(3);
    ASSERT_TRUE(failure.has_value());
    EXPECT_EQ(failure->code(), ErrorCode::IoError);
    EXPECT_EQ(failure->message(), "page 3: injected failure");
    EXPECT_FALSE(cache->failure(2).has_value());
    for (const std::uint64_t page : {0u, 1u, 2u, 4u, 5u})
        EXPECT_EQ(cache->state(page), PageState::Resident) << page;

    for (int frame = 0; frame < 3; ++frame) {
        cache->beginFrame();
        EXPECT_FALSE(cache->tryGet(3).has_value());
        cache->request(3, 100.0f);
        EXPECT_EQ(cache->state(3), PageState::Failed);
        cache->request(6 + static_cast<std::uint64_t>(frame), 1.0f); // others keep streaming
        cache->endFrame();
        cache->drain();
    }
    EXPECT_EQ(source->readCount(3), 1u);
    EXPECT_EQ(cache->stats().failed, 1u);
    for (std::uint64_t page = 6; page < 9; ++page)
        EXPECT_EQ(cache->state(page), PageState::Resident);
}

TEST(PageCacheTest, APageBeyondTheSourceFailsWithoutAReadIn) {
    auto source = std::make_shared<FakePageSource>(kPageSize, 10);
    auto cache = makeCache(source, makeOptions(16 * kPageSize));
    cache->beginFrame();
    cache->request(10, 1.0f);
    EXPECT_EQ(cache->state(10), PageState::Failed);
    EXPECT_EQ(cache->failure(10)->code(), ErrorCode::InvalidArgument);
    cache->request(10, 1.0f);
    EXPECT_EQ(cache->stats().failed, 1u);
    EXPECT_EQ(cache->stats().requests, 0u);
    EXPECT_EQ(source->readCount(10), 0u);
}

// ---- hysteresis ---------------------------------------------------------------------------

TEST(PageCacheTest, AWorkingSetExactlyAtTheBudgetIsNeverEvicted) {
    auto source = std::make_shared<FakePageSource>(kPageSize, 20);
    auto cache = makeCache(source, makeOptions(10 * kPageSize, 2, 64, 0.2));
    for (int frame = 0; frame < 100; ++frame) {
        cache->beginFrame();
        for (std::uint64_t page = 0; page < 10; ++page) {
            if (!cache->tryGet(page))
                cache->request(page, 1.0f);
        }
        cache->endFrame();
        cache->drain();
    }
    EXPECT_EQ(cache->stats().evicted, 0u);
    EXPECT_EQ(cache->stats().completed, 10u);
    EXPECT_EQ(cache->stats().residentBytes, 10u * kPageSize);
}

/** Frames in which something was evicted, for a window of 5 pages sliding one page per frame
 *  over a budget of 10 pages. */
int framesWithEvictions(double hysteresis) {
    auto source = std::make_shared<FakePageSource>(kPageSize, 200);
    auto cache = makeCache(source, makeOptions(10 * kPageSize, 1, 64, hysteresis));
    int frames = 0;
    for (std::uint64_t frame = 0; frame < 150; ++frame) {
        const std::uint64_t evictedBefore = cache->stats().evicted;
        cache->beginFrame();
        for (std::uint64_t page = frame; page < frame + 5; ++page) {
            if (!cache->tryGet(page))
                cache->request(page, 1.0f);
        }
        cache->endFrame();
        cache->drain();
        EXPECT_TRUE(withinBudget(*cache));
        EXPECT_EQ(cache->stats().dropped, 0u);
        if (cache->stats().evicted != evictedBefore)
            ++frames;
    }
    return frames;
}

TEST(PageCacheTest, HysteresisEvictsInBatchesRatherThanEveryFrame) {
    const int without = framesWithEvictions(0.0);
    const int with = framesWithEvictions(0.5);
    // Without hysteresis each new page evicts one old page, every frame once full (frame 10 on).
    EXPECT_GE(without, 139);
    // With it, eviction goes down to 5 pages after install, so it happens every 5th frame.
    EXPECT_LE(with, 30);
    EXPECT_GT(with, 0);
}

// ---- shutdown -----------------------------------------------------------------------------

TEST(PageCacheTest, DestructionWithReadsBlockedInFlightIsClean) {
    auto source = std::make_shared<FakePageSource>(kPageSize, 40);
    source->closeGate();
    auto cache = makeCache(source, makeOptions(8 * kPageSize, 2, 32));
    cache->beginFrame();
    for (std::uint64_t page = 0; page < 20; ++page)
        cache->request(page, 1.0f);
    source->waitUntilBlocked(2); // both I/O threads are inside readPage
    // The destructor cancels the queue and joins; the joined reads can only finish once the
    // gate opens, which this thread does while the other one destroys.
    std::thread destroyer([doomed = std::move(cache)]() mutable { doomed.reset(); });
    source->openGate();
    destroyer.join();
    EXPECT_GE(source->readOrder().size(), 2u); // the two blocked reads ran; destruction joined them
}

TEST(PageCacheTest, DestructionWithCompletionsNotPumpedFreesThem) {
    auto source = std::make_shared<FakePageSource>(kPageSize, 40);
    auto cache = makeCache(source, makeOptions(8 * kPageSize, 2, 32));
    cache->beginFrame();
    for (std::uint64_t page = 0; page < 20; ++page)
        cache->request(page, 1.0f);
    source->waitUntilFinished(20);
    cache.reset(); // LeakSanitizer checks that the 20 buffers were freed
    EXPECT_EQ(source->readOrder().size(), 20u);
}

// ---- threading contract -------------------------------------------------------------------

// ---- pins -------------------------------------------------------------------------------------

TEST(PageCacheTest, APinnedPageIsNeverEvictedUntilItsPinIsReleased) {
    auto source = std::make_shared<FakePageSource>(kPageSize, 64);
    auto cache = makeCache(source, makeOptions(4 * kPageSize));
    ASSERT_NE(cache, nullptr);
    loadPages(*cache, {0, 1, 2, 3});
    storage::PagePin pin = cache->pin(0);
    ASSERT_FALSE(pin.empty());
    EXPECT_TRUE(holdsPage(pin.bytes(), 0));
    for (std::uint64_t first = 4; first < 40; first += 3) {
        loadPages(*cache, range(first, first + 3)); // every frame evicts
        ASSERT_TRUE(withinBudget(*cache));
        ASSERT_EQ(cache->state(0), PageState::Resident) << first;
        ASSERT_TRUE(holdsPage(pin.bytes(), 0));
    }
    pin.reset();
    loadPages(*cache, range(40, 44));
    EXPECT_EQ(cache->state(0), PageState::Absent);
    EXPECT_TRUE(withinBudget(*cache));
    EXPECT_TRUE(cache->pin(0).empty()); // not resident: nothing to pin
}

TEST(PageCacheTest, WhenPinsHoldTheBudgetCompletionsAreDroppedNotForced) {
    auto source = std::make_shared<FakePageSource>(kPageSize, 16);
    auto cache = makeCache(source, makeOptions(2 * kPageSize));
    ASSERT_NE(cache, nullptr);
    loadPages(*cache, {0, 1});
    storage::PagePin a = cache->pin(0);
    storage::PagePin b = cache->pin(1);
    const std::uint64_t droppedBefore = cache->stats().dropped;
    loadPages(*cache, {2, 3});
    EXPECT_EQ(cache->stats().dropped, droppedBefore + 2);
    EXPECT_EQ(cache->state(2), PageState::Absent);
    EXPECT_TRUE(withinBudget(*cache));
    b.reset();
    loadPages(*cache, {2});
    EXPECT_EQ(cache->state(2), PageState::Resident);
    EXPECT_EQ(cache->state(0), PageState::Resident);
}

TEST(PageCacheTest, APinKeepsItsBytesAfterTheCacheIsGone) {
    auto source = std::make_shared<FakePageSource>(kPageSize, 8);
    storage::PagePin pin;
    {
        auto cache = makeCache(source, makeOptions(4 * kPageSize));
        ASSERT_NE(cache, nullptr);
        loadPages(*cache, {5});
        pin = cache->pin(5);
    }
    ASSERT_EQ(pin.bytes().size(), kPageSize);
    EXPECT_TRUE(holdsPage(pin.bytes(), 5)); // ASan: no use after free
}

TEST(PageCacheTest, APinMayBeReleasedOnAnotherThread) {
    auto source = std::make_shared<FakePageSource>(kPageSize, 32);
    auto cache = makeCache(source, makeOptions(2 * kPageSize));
    ASSERT_NE(cache, nullptr);
    for (int round = 0; round < 20; ++round) {
        const auto page = static_cast<std::uint64_t>(round);
        loadPages(*cache, {page});
        storage::PagePin pin = cache->pin(page);
        ASSERT_FALSE(pin.empty());
        std::thread reader([held = std::move(pin), page]() mutable {
            EXPECT_TRUE(holdsPage(held.bytes(), page));
            held.reset();
        });
        reader.join();
        ASSERT_TRUE(withinBudget(*cache));
    }
    EXPECT_GT(cache->stats().evicted, 0u); // released pins left their pages evictable
}

TEST(PageCacheDeathTest, MainThreadMethodsAssertTheirThread) {
#ifdef NDEBUG
    GTEST_SKIP() << "FF_ASSERT is off in this build";
#else
    GTEST_FLAG_SET(death_test_style, "threadsafe");
    auto source = std::make_shared<FakePageSource>(kPageSize, 4);
    auto cache = makeCache(source, makeOptions(4 * kPageSize, 1));
    PageCache* raw = cache.get();
    EXPECT_DEATH(
            {
                std::thread other([raw] { raw->beginFrame(); });
                other.join();
            },
            "assertion failed");
#endif
}

} // namespace
} // namespace ff::cache
