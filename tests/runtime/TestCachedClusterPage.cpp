// Format v2's geometry pages on their way to the GPU: kept encoded by the page cache behind their
// cluster table (indexed once on its worker threads, budgeted at about their size in the file),
// reached by a frame through the cached page access (the trailer still last) and found again per
// node by its representation's range; then decoded, a frame ahead of their upload, by the decode
// stage's threads.

#include "CachedClusterPage.h"
#include "CachedPageAccess.h"
#include "ClusterPatches.h"
#include "GeometryDecodeStage.h"

#include <ff/cache/PageCache.h>
#include <ff/storage/ClusterPage.h>
#include <ff/storage/PageSource.h>

#include <gtest/gtest.h>

#include <cstring>
#include <memory>
#include <vector>

namespace ff::runtime {
namespace {

using storage::test::encode;
using storage::test::makePatch;
using storage::test::Patch;

constexpr std::uint32_t kPageSize = 16u << 10;

/** Pages held in memory with their trailers (the cache does not verify; sources do). */
class PagesInMemory final : public storage::IPageSource {
public:
    std::uint64_t add(storage::PageType type, std::span<const std::byte> payload) {
        std::vector<std::byte> page(kPageSize);
        std::memcpy(page.data(), payload.data(), payload.size());
        const storage::PageTrailer trailer{
                static_cast<std::uint32_t>(mPages.size()),
                static_cast<std::uint16_t>(type),
                storage::kPageTrailerMagic,
                0};
        std::memcpy(page.data() + storage::pagePayloadBytes(kPageSize), &trailer, sizeof(trailer));
        mPages.push_back(std::move(page));
        return mPages.size() - 1;
    }
    std::uint32_t pageSize() const override { return kPageSize; }
    std::uint64_t pageCount() const override { return mPages.size(); }
    Status readPage(std::uint64_t index, std::span<std::byte> out) override {
        std::memcpy(out.data(), mPages.at(index).data(), out.size());
        return Status::ok();
    }
    std::vector<std::byte>& bytes(std::uint64_t page) { return mPages.at(page); }

private:
    std::vector<std::vector<std::byte>> mPages;
};

storage::PositionGrid grid(float origin) {
    auto g = storage::PositionGrid::covering(
            {origin, origin, origin}, {origin + 4, origin + 4, origin + 4});
    EXPECT_TRUE(g.isOk());
    return *g;
}

class CachedClusterPageTest : public ::testing::Test {
protected:
    void SetUp() override {
        mGrids = {grid(0.0f), grid(100.0f)};
        for (std::uint32_t prototype = 0; prototype < 2; ++prototype) {
            storage::ClusterPageWriter writer(kPageSize, prototype);
            for (std::uint32_t node = 0; node < 3; ++node) {
                const Patch patch = makePatch(
                        5 + static_cast<int>(node),
                        6,
                        17,
                        {200 * node, 40, 9},
                        prototype * 10 + node);
                const std::vector<std::byte> cluster = encode(patch);
                const auto offset = writer.append(cluster, 1);
                ASSERT_TRUE(offset.isOk()) << offset.status().toString();
                mNodes.push_back(
                        {prototype, *offset, static_cast<std::uint32_t>(cluster.size()), patch});
            }
            mGeometryPages.push_back(mSource->add(storage::PageType::Geometry, writer.bytes()));
        }
        const std::vector<std::byte> nodes(100, std::byte{0x5A});
        mNodePage = mSource->add(storage::PageType::Nodes, nodes);
    }

    std::unique_ptr<cache::PageCache> makeCache(std::uint64_t budget) {
        cache::PageCacheOptions options;
        options.budgetBytes = budget;
        options.decoder = std::make_shared<ClusterPageIndexer>(mGrids);
        auto made = cache::PageCache::create(mSource, options);
        EXPECT_TRUE(made.isOk()) << made.status().toString();
        return made.isOk() ? std::move(*made) : nullptr;
    }

    /** Reads the geometry pages into the cache (one frame). */
    static void readIn(cache::PageCache& cache, std::span<const std::uint64_t> pages) {
        cache.beginFrame();
        for (const std::uint64_t page : pages)
            cache.request(page, 1.0f);
        cache.endFrame();
        cache.drain();
    }
    /** A geometry page's payload as the cache keeps it (trailer cut off). */
    std::vector<std::byte> cachedPayload(cache::PageCache& cache, std::uint64_t page) {
        readIn(cache, std::span(&page, 1));
        const storage::PagePin pin = cache.pin(page);
        EXPECT_FALSE(pin.empty());
        if (pin.empty())
            return {};
        return {pin.bytes().begin(), pin.bytes().end() - sizeof(storage::PageTrailer)};
    }

    struct Node {
        std::uint32_t prototype;
        std::uint32_t offset;
        std::uint32_t length;
        Patch patch;
    };
    std::vector<storage::PositionGrid> mGrids;
    std::shared_ptr<PagesInMemory> mSource = std::make_shared<PagesInMemory>();
    std::vector<std::uint64_t> mGeometryPages;
    std::uint64_t mNodePage = 0;
    std::vector<Node> mNodes;
};

TEST_F(CachedClusterPageTest, AFrameFindsEachNodesClustersInThePageKeptEncoded) {
    auto cache = makeCache(4u << 20);
    ASSERT_NE(cache, nullptr);
    CachedPageAccess pages(*cache);
    // Frame 1 asks, the reads complete, frame 2 finds everything resident.
    pages.beginFrame();
    for (const std::uint64_t page : mGeometryPages)
        EXPECT_EQ(
                pages.lookup(page, storage::PageType::Geometry, 1.0f).availability,
                PageAvailability::Pending);
    EXPECT_EQ(
            pages.lookup(mNodePage, storage::PageType::Nodes, 1.0f).availability,
            PageAvailability::Pending);
    pages.endFrame();
    cache->drain();

    pages.beginFrame();
    for (const Node& node : mNodes) {
        const PageLookup lookup =
                pages.lookup(mGeometryPages[node.prototype], storage::PageType::Geometry, 1.0f);
        ASSERT_EQ(lookup.availability, PageAvailability::Ready);
        const auto page = CachedClusterPage::view(lookup.payload);
        ASSERT_TRUE(page.isOk()) << page.status().toString();
        EXPECT_EQ(page->prototype(), node.prototype);
        // Kept encoded: the page's used bytes and a table of its three clusters, no more.
        EXPECT_LE(
                lookup.payload.size(),
                page->encoded().size() + 32 + 3 * sizeof(storage::IndexedCluster) + 3);
        EXPECT_LT(page->encoded().size(), kPageSize);
        const auto run = page->run(node.offset, node.length, 1);
        ASSERT_TRUE(run.isOk()) << run.status().toString();
        const storage::IndexedCluster& cluster = page->clusters()[run->first];
        ASSERT_EQ(cluster.info.vertexCount, node.patch.vertices.size());
        // Decoded on the position grid of the page's prototype, indices cluster-local.
        const auto decoded =
                decodeCachedPage(*page, mGrids, storage::maxDecodedClusterBytes(kPageSize));
        ASSERT_TRUE(decoded.isOk()) << decoded.status().toString();
        ASSERT_EQ(decoded->vertexCount, page->vertexCount());
        for (std::size_t v = 0; v < node.patch.vertices.size(); ++v)
            ASSERT_EQ(
                    decoded->vertices()[cluster.firstVertex + v].position,
                    mGrids[node.prototype].position(node.patch.vertices[v].coordinate));
        for (std::size_t i = 0; i < node.patch.indices.size(); ++i)
            ASSERT_LT(decoded->indices()[cluster.firstIndex + i], cluster.info.vertexCount);
        EXPECT_LE(
                lookup.payload.size() + sizeof(storage::PageTrailer),
                ClusterPageIndexer({}).maxDecodedBytes(kPageSize));
    }
    // The node page is kept as read.
    const PageLookup nodes = pages.lookup(mNodePage, storage::PageType::Nodes, 1.0f);
    ASSERT_EQ(nodes.availability, PageAvailability::Ready);
    EXPECT_EQ(nodes.payload.size(), storage::pagePayloadBytes(kPageSize));
    EXPECT_EQ(nodes.payload[0], std::byte{0x5A});
    // The type check of the cached access still sees the trailer, indexed or not.
    EXPECT_EQ(
            pages.lookup(mGeometryPages[0], storage::PageType::Nodes, 1.0f).availability,
            PageAvailability::Failed);
    pages.endFrame();
}

TEST_F(CachedClusterPageTest, DecodingRefusesATableThatRunsPastThePageOrDecodesPastItsBound) {
    auto cache = makeCache(4u << 20);
    ASSERT_NE(cache, nullptr);
    std::vector<std::byte> bytes = cachedPayload(*cache, mGeometryPages[0]);
    const auto page = CachedClusterPage::view(bytes);
    ASSERT_TRUE(page.isOk());
    // A bound below what the page decodes to.
    const auto bounded = decodeCachedPage(*page, mGrids, 10);
    ASSERT_FALSE(bounded.isOk());
    EXPECT_EQ(bounded.status().code(), ErrorCode::Corrupt);
    // The last cluster's first vertex moved past the page's vertices.
    auto* table = reinterpret_cast<storage::IndexedCluster*>(bytes.data() + 32);
    const std::uint32_t lastFirstVertex = table[2].firstVertex;
    table[2].firstVertex = page->vertexCount();
    const auto overrun = decodeCachedPage(
            *CachedClusterPage::view(bytes), mGrids, storage::maxDecodedClusterBytes(kPageSize));
    ASSERT_FALSE(overrun.isOk());
    EXPECT_NE(overrun.status().message().find("runs past"), std::string::npos)
            << overrun.status().toString();
    // A table that gives a cluster fewer vertices than its own header: refused, not overrun.
    table[2].firstVertex = lastFirstVertex;
    table[1].info.vertexCount -= 1;
    const auto disagreeing = decodeCachedPage(
            *CachedClusterPage::view(bytes), mGrids, storage::maxDecodedClusterBytes(kPageSize));
    ASSERT_FALSE(disagreeing.isOk());
    EXPECT_EQ(disagreeing.status().code(), ErrorCode::Corrupt);
    // Not a cached page at all, and every prefix of one.
    EXPECT_FALSE(CachedClusterPage::view(std::vector<std::byte>(64)).isOk());
    for (std::size_t n = 0; n < bytes.size(); ++n)
        ASSERT_FALSE(CachedClusterPage::view(std::span(bytes).first(n)).isOk()) << n;
}

TEST_F(CachedClusterPageTest, ACorruptClusterPageOrAnUnknownPrototypeFailsThePageNamingIt) {
    mSource->bytes(mGeometryPages[0])[20] ^= std::byte{0xFF}; // the first cluster's header
    mGrids.resize(1);                                         // page 2 names prototype 1
    auto cache = makeCache(4u << 20);
    ASSERT_NE(cache, nullptr);
    cache->beginFrame();
    for (const std::uint64_t page : mGeometryPages)
        cache->request(page, 1.0f);
    cache->endFrame();
    cache->drain();
    for (const std::uint64_t page : mGeometryPages) {
        ASSERT_EQ(cache->state(page), cache::PageState::Failed) << page;
        const std::string message = cache->failure(page)->message();
        EXPECT_EQ(message.rfind("page " + std::to_string(page) + ": cluster page", 0), 0u)
                << message;
    }
    EXPECT_NE(cache->failure(mGeometryPages[1])->message().find("prototype 1"), std::string::npos);
}

TEST_F(CachedClusterPageTest, ABudgetBelowOneCachedPageIsRefused) {
    cache::PageCacheOptions options;
    options.budgetBytes =
            2 * kPageSize; // two pages as read, less than one page and its table may take
    options.decoder = std::make_shared<ClusterPageIndexer>(mGrids);
    const auto made = cache::PageCache::create(mSource, options);
    ASSERT_FALSE(made.isOk());
    EXPECT_EQ(made.status().code(), ErrorCode::InvalidArgument);
}

// ---- The decode stage between the cache and the GPU arena ----------------------------------

TEST_F(CachedClusterPageTest, TheStageDecodesAPageForTheFrameAfterItIsAskedAndFreesItOnceUploaded) {
    auto cache = makeCache(4u << 20);
    ASSERT_NE(cache, nullptr);
    const std::uint64_t page = mGeometryPages[1];
    const std::vector<std::byte> cached = cachedPayload(*cache, page);
    const auto expected = decodeCachedPage(
            *CachedClusterPage::view(cached), mGrids, storage::maxDecodedClusterBytes(kPageSize));
    ASSERT_TRUE(expected.isOk());

    auto created = GeometryDecodeStage::create(*cache, mGrids, kPageSize, {2, 8});
    ASSERT_TRUE(created.isOk()) << created.status().message();
    GeometryDecodeStage& stage = **created;
    stage.beginFrame();
    EXPECT_FALSE(stage.prepare(page));
    stage.drain();
    // Decoded, but answers hold for the frame: it is ready from the next one.
    EXPECT_FALSE(stage.prepare(page));
    EXPECT_EQ(stage.decoded(page), nullptr);
    EXPECT_EQ(stage.stats().requested, 1u);

    stage.beginFrame();
    ASSERT_TRUE(stage.prepare(page));
    const DecodedGeometry* decoded = stage.decoded(page);
    ASSERT_NE(decoded, nullptr);
    ASSERT_EQ(decoded->size(), expected->size());
    EXPECT_EQ(std::memcmp(decoded->bytes.get(), expected->bytes.get(), decoded->size()), 0);
    EXPECT_EQ(stage.stats().decoded, 1u);
    EXPECT_EQ(stage.stats().decodedBytes, expected->size());
    EXPECT_EQ(stage.stats().heldBytes, expected->size());
    // Uploaded: the GPU has it, the decoded copy is freed at once, and so is its room.
    stage.uploaded(page);
    EXPECT_EQ(stage.decoded(page), nullptr);
    EXPECT_EQ(stage.stats().heldBytes, 0u);
    EXPECT_EQ(stage.stats().dropped, 0u);
    EXPECT_EQ(stage.stats().peakHeldBytes, expected->size());
    // Asked again a later frame (the arena evicted it): decoded again.
    stage.beginFrame();
    EXPECT_FALSE(stage.prepare(page));
    EXPECT_EQ(stage.stats().requested, 2u);
}

TEST_F(CachedClusterPageTest, TheStageHoldsNoMoreThanItsCapacityAndFreesWhatIsNotAskedForAgain) {
    auto cache = makeCache(4u << 20);
    ASSERT_NE(cache, nullptr);
    readIn(*cache, mGeometryPages);
    auto created = GeometryDecodeStage::create(*cache, mGrids, kPageSize, {1, 1});
    ASSERT_TRUE(created.isOk()) << created.status().message();
    GeometryDecodeStage& stage = **created;
    stage.beginFrame();
    EXPECT_FALSE(stage.prepare(mGeometryPages[0]));
    EXPECT_FALSE(stage.prepare(mGeometryPages[1])); // over capacity: not queued
    EXPECT_EQ(stage.stats().requested, 1u);
    EXPECT_EQ(stage.stats().refused, 1u);
    stage.drain();
    // Asked in the frame that just ended: kept, and ready.
    stage.beginFrame();
    EXPECT_GT(stage.stats().heldBytes, 0u);
    EXPECT_EQ(stage.stats().decoded, 1u);
    // Not asked for in this frame: freed at the next (dropped, not uploaded), room again.
    stage.beginFrame();
    EXPECT_EQ(stage.stats().heldBytes, 0u);
    EXPECT_EQ(stage.stats().dropped, 1u);
    EXPECT_EQ(stage.decoded(mGeometryPages[0]), nullptr);
    // A page not resident in the cache is not queued (the traversal asks the cache for it),
    // though there is room.
    EXPECT_FALSE(stage.prepare(mNodePage));
    EXPECT_EQ(stage.stats().requested, 1u);
    EXPECT_EQ(stage.stats().refused, 1u);
    EXPECT_FALSE(stage.prepare(mGeometryPages[1]));
    EXPECT_EQ(stage.stats().requested, 2u);
    stage.drain();
    stage.beginFrame();
    stage.beginFrame();
    // Whatever was queued was decoded or cancelled; nothing is held.
    EXPECT_EQ(stage.stats().requested, stage.stats().decoded + stage.stats().cancelled);
    EXPECT_EQ(stage.stats().heldBytes, 0u);
}

TEST_F(CachedClusterPageTest, APageTheStageCannotDecodeFailsOnceNamingIt) {
    auto cache = makeCache(4u << 20);
    ASSERT_NE(cache, nullptr);
    readIn(*cache, mGeometryPages);
    // The stage knows only prototype 0's grid; the second page is prototype 1's.
    auto created = GeometryDecodeStage::create(*cache, {mGrids[0]}, kPageSize);
    ASSERT_TRUE(created.isOk()) << created.status().message();
    GeometryDecodeStage& stage = **created;
    stage.beginFrame();
    EXPECT_FALSE(stage.prepare(mGeometryPages[1]));
    stage.drain();
    stage.beginFrame();
    const std::vector<Status> failures = stage.takeFailures();
    ASSERT_EQ(failures.size(), 1u);
    EXPECT_EQ(failures[0].code(), ErrorCode::Corrupt);
    const std::string message = failures[0].message();
    EXPECT_EQ(message.rfind("page " + std::to_string(mGeometryPages[1]) + ": ", 0), 0u) << message;
    EXPECT_NE(message.find("prototype 1"), std::string::npos) << message;
    // Never asked for again, never reported again.
    EXPECT_FALSE(stage.prepare(mGeometryPages[1]));
    EXPECT_EQ(stage.stats().requested, 1u);
    EXPECT_EQ(stage.stats().failed, 1u);
    EXPECT_TRUE(stage.takeFailures().empty());
}

} // namespace
} // namespace ff::runtime
