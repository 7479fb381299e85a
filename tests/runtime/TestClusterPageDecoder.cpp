// Format v2's geometry pages through the page cache's decode stage: decoded once on the worker
// threads, kept compact and budgeted as decoded, reached by a frame through the cached page
// access (the trailer still last), and found again per node by its representation's range.

#include "CachedPageAccess.h"
#include "ClusterPageDecoder.h"
#include "ClusterPatches.h"

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

class ClusterPageDecoderTest : public ::testing::Test {
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
        options.decoder = std::make_shared<ClusterPageDecoder>(mGrids);
        auto made = cache::PageCache::create(mSource, options);
        EXPECT_TRUE(made.isOk()) << made.status().toString();
        return made.isOk() ? std::move(*made) : nullptr;
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

TEST_F(ClusterPageDecoderTest, AFrameReadsEachNodesClustersFromThePageDecodedOnce) {
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
    std::uint64_t decodedBytes = 0;
    for (const Node& node : mNodes) {
        const PageLookup lookup =
                pages.lookup(mGeometryPages[node.prototype], storage::PageType::Geometry, 1.0f);
        ASSERT_EQ(lookup.availability, PageAvailability::Ready);
        const auto page = DecodedClusterPage::view(lookup.payload);
        ASSERT_TRUE(page.isOk()) << page.status().toString();
        EXPECT_EQ(page->prototype(), node.prototype);
        const auto run = page->run(node.offset, node.length, 1);
        ASSERT_TRUE(run.isOk()) << run.status().toString();
        const storage::IndexedCluster& cluster = page->clusters()[run->first];
        ASSERT_EQ(cluster.info.vertexCount, node.patch.vertices.size());
        for (std::size_t v = 0; v < node.patch.vertices.size(); ++v)
            ASSERT_EQ(
                    page->vertices()[cluster.firstVertex + v].position,
                    mGrids[node.prototype].position(node.patch.vertices[v].coordinate));
        for (std::size_t i = 0; i < node.patch.indices.size(); ++i)
            ASSERT_LT(page->indices()[cluster.firstIndex + i], cluster.info.vertexCount);
        decodedBytes = std::max<std::uint64_t>(decodedBytes, lookup.payload.size());
    }
    // The node page is kept as read; the budget counts the decoded pages as they are kept.
    const PageLookup nodes = pages.lookup(mNodePage, storage::PageType::Nodes, 1.0f);
    ASSERT_EQ(nodes.availability, PageAvailability::Ready);
    EXPECT_EQ(nodes.payload.size(), storage::pagePayloadBytes(kPageSize));
    EXPECT_EQ(nodes.payload[0], std::byte{0x5A});
    EXPECT_GT(cache->stats().bytesDecoded, 0u);
    EXPECT_LE(decodedBytes, ClusterPageDecoder({}).maxDecodedBytes(kPageSize));
    // The type check of the cached access still sees the trailer, decoded or not.
    EXPECT_EQ(
            pages.lookup(mGeometryPages[0], storage::PageType::Nodes, 1.0f).availability,
            PageAvailability::Failed);
    pages.endFrame();
}

TEST_F(ClusterPageDecoderTest, ACorruptClusterPageOrAnUnknownPrototypeFailsThePageNamingIt) {
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

TEST_F(ClusterPageDecoderTest, ABudgetBelowOneDecodedPageIsRefused) {
    cache::PageCacheOptions options;
    options.budgetBytes = 2 * kPageSize; // two pages as read, less than one decoded page may take
    options.decoder = std::make_shared<ClusterPageDecoder>(mGrids);
    const auto made = cache::PageCache::create(mSource, options);
    ASSERT_FALSE(made.isOk());
    EXPECT_EQ(made.status().code(), ErrorCode::InvalidArgument);
}

} // namespace
} // namespace ff::runtime
