// Format v2's geometry pages: payloads of whole clusters placed in a page, found again by their
// (offset, length, count), decoded whole; every prefix and random bit flips refused or harmless.

#include "ClusterPatches.h"

#include <ff/storage/ClusterPage.h>
#include <ff/storage/SceneFormat.h>

#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <vector>

namespace ff::storage {
namespace {

using test::encode;
using test::makePatch;
using test::Patch;
using test::testGrid;

constexpr std::uint32_t kPageSize = 16u << 10;
constexpr std::uint32_t kPrototype = 7;

/** A node's payload: a few patches encoded back to back. */
struct Payload {
    std::vector<Patch> patches;
    std::vector<std::byte> bytes;
    std::uint32_t offset = 0;
};

Payload makePayload(int patches, std::uint32_t seed) {
    Payload p;
    for (int i = 0; i < patches; ++i) {
        const auto n = static_cast<std::uint32_t>(i);
        p.patches.push_back(makePatch(4 + i, 5, 11, {100 * (seed + n), 300, 50}, seed * 10 + n));
        const std::vector<std::byte> cluster = encode(p.patches.back());
        p.bytes.insert(p.bytes.end(), cluster.begin(), cluster.end());
    }
    return p;
}

class ClusterPageTest : public ::testing::Test {
protected:
    void SetUp() override {
        ClusterPageWriter writer(kPageSize, kPrototype);
        for (std::uint32_t node = 0; node < 5; ++node) {
            Payload p = makePayload(1 + static_cast<int>(node % 3), node + 1);
            ASSERT_TRUE(writer.fits(p.bytes, static_cast<std::uint32_t>(p.patches.size())));
            const auto offset =
                    writer.append(p.bytes, static_cast<std::uint32_t>(p.patches.size()));
            ASSERT_TRUE(offset.isOk()) << offset.status().toString();
            p.offset = *offset;
            mPayloads.push_back(std::move(p));
        }
        const std::span<const std::byte> bytes = writer.bytes();
        mPage.assign(bytes.begin(), bytes.end());
    }

    std::vector<Payload> mPayloads;
    std::vector<std::byte> mPage;
};

TEST_F(ClusterPageTest, PayloadsAreFoundAgainAndDecodeToTheirClusters) {
    const auto index = indexClusterPage(mPage, kPageSize);
    ASSERT_TRUE(index.isOk()) << index.status().toString();
    EXPECT_EQ(index->prototype, kPrototype);
    EXPECT_EQ(index->clusters.size(), 1u + 2u + 3u + 1u + 2u);
    std::vector<PackedVertex> vertices(index->vertexCount);
    std::vector<std::uint8_t> indices(index->indexCount);
    const PositionGrid grid = testGrid();
    ASSERT_TRUE(decodeClusterPage(mPage, *index, grid, vertices, indices).isOk());

    for (const Payload& p : mPayloads) {
        const auto run = findClusterRun(
                index->clusters,
                p.offset,
                static_cast<std::uint32_t>(p.bytes.size()),
                static_cast<std::uint32_t>(p.patches.size()));
        ASSERT_TRUE(run.isOk()) << run.status().toString();
        ASSERT_EQ(run->count, p.patches.size());
        for (std::uint32_t c = 0; c < run->count; ++c) {
            const IndexedCluster& cluster = index->clusters[run->first + c];
            const Patch& patch = p.patches[c];
            ASSERT_EQ(cluster.info.vertexCount, patch.vertices.size());
            for (std::size_t v = 0; v < patch.vertices.size(); ++v)
                EXPECT_EQ(
                        vertices[cluster.firstVertex + v].position,
                        grid.position(patch.vertices[v].coordinate));
            ASSERT_EQ(std::size_t{cluster.info.triangleCount} * 3, patch.indices.size());
        }
    }
}

TEST_F(ClusterPageTest, ARangeThatIsNotExactlyARunOfClustersIsRefused) {
    const auto index = indexClusterPage(mPage, kPageSize);
    ASSERT_TRUE(index.isOk());
    const Payload& p = mPayloads[2]; // three clusters
    const auto length = static_cast<std::uint32_t>(p.bytes.size());
    EXPECT_FALSE(findClusterRun(index->clusters, p.offset + 1, length, 3).isOk()); // not at a cluster
    EXPECT_FALSE(findClusterRun(index->clusters, p.offset, length - 1, 3).isOk()); // ends inside one
    EXPECT_FALSE(findClusterRun(index->clusters, p.offset, length, 2).isOk());     // counts disagree
    EXPECT_FALSE(findClusterRun(index->clusters, p.offset, length, 0).isOk());
    EXPECT_FALSE(findClusterRun(index->clusters, p.offset, length, 60000).isOk());
    EXPECT_FALSE(findClusterRun(index->clusters, 0xFFFFFFF0u, 100, 1).isOk());
    EXPECT_TRUE(findClusterRun(index->clusters, p.offset, length, 3).isOk());
}

TEST_F(ClusterPageTest, TheWriterRefusesWhatIsNotWholeClustersOrDoesNotFit) {
    ClusterPageWriter writer(kPageSize, 0);
    const Payload p = makePayload(2, 9);
    EXPECT_FALSE(writer.append(p.bytes, 3).isOk()); // fewer clusters than said
    EXPECT_FALSE(writer.append(p.bytes, 1).isOk()); // more bytes than one cluster
    EXPECT_FALSE(writer.append(std::span(p.bytes).first(p.bytes.size() - 1), 2).isOk());
    EXPECT_TRUE(writer.empty());
    std::uint32_t appended = 0;
    while (writer.fits(p.bytes, 2)) {
        ASSERT_TRUE(writer.append(p.bytes, 2).isOk());
        ++appended;
    }
    EXPECT_GT(appended, 3u);
    EXPECT_FALSE(writer.append(p.bytes, 2).isOk());
    const std::span<const std::byte> bytes = writer.bytes();
    const auto index = indexClusterPage(bytes, kPageSize);
    ASSERT_TRUE(index.isOk()) << index.status().toString();
    EXPECT_EQ(index->clusters.size(), 2u * appended);
}

// Clusters that compress well decode to many times their bytes: the page stops at 3 x its size
// decoded, so what the cache budgets for a read in flight holds.
TEST(ClusterPageLimitTest, APageDecodesToAtMostThreeTimesItsSize) {
    constexpr std::uint32_t kSmallPage = 4096;
    Patch flat = makePatch(16, 15, 3, {10, 10, 10}, 5);
    for (ClusterVertex& v : flat.vertices) { // one normal, one colour: the codec's best case
        v.normalOct = {100, 200};
        v.color = {9, 9, 9, 255};
        v.coordinate[2] = 10;
    }
    const std::vector<std::byte> cluster = encode(flat);
    const std::uint64_t decoded = decodedClusterBytes(flat.vertices.size(), flat.indices.size());
    ASSERT_GT(decoded, 4 * cluster.size()); // the premise: it expands

    ClusterPageWriter writer(kSmallPage, 0);
    std::uint32_t placed = 0;
    while (writer.fits(cluster, 1)) {
        ASSERT_TRUE(writer.append(cluster, 1).isOk());
        ++placed;
    }
    EXPECT_EQ(placed, maxDecodedClusterBytes(kSmallPage) / decoded);
    EXPECT_LT(
            kClusterPageHeaderSize + placed * cluster.size() + cluster.size(),
            pagePayloadBytes(kSmallPage))
            << "the bytes would fit: the decoded size stops it";
    const auto refused = writer.append(cluster, 1);
    EXPECT_FALSE(refused.isOk());
    EXPECT_NE(refused.status().message().find("decoded"), std::string::npos)
            << refused.status().message();

    const std::span<const std::byte> page = writer.bytes();
    ASSERT_TRUE(indexClusterPage(page, kSmallPage).isOk());

    // A reader checks it too: a 16 KiB page of these clusters, read against a 4 KiB page's limit.
    ClusterPageWriter large(4 * kSmallPage, 0);
    while (large.fits(cluster, 1))
        ASSERT_TRUE(large.append(cluster, 1).isOk());
    ASSERT_GT(large.clusterCount() * decoded, maxDecodedClusterBytes(kSmallPage));
    const auto over = indexClusterPage(large.bytes(), kSmallPage);
    ASSERT_FALSE(over.isOk());
    EXPECT_NE(over.status().message().find("decodes to"), std::string::npos)
            << over.status().message();
    EXPECT_TRUE(indexClusterPage(large.bytes(), 4 * kSmallPage).isOk());
}

TEST_F(ClusterPageTest, EveryPrefixIsRefusedCleanly) {
    const auto index = indexClusterPage(mPage, kPageSize);
    ASSERT_TRUE(index.isOk());
    for (std::size_t size = 0; size < index->usedBytes; ++size) {
        const auto cut = indexClusterPage(std::span(mPage).first(size), kPageSize);
        ASSERT_FALSE(cut.isOk()) << size;
        ASSERT_EQ(cut.status().code(), ErrorCode::Corrupt) << size;
    }
}

TEST_F(ClusterPageTest, RandomBitFlipsAreRefusedOrDecodeWithoutHarm) {
    std::mt19937 random(99);
    const auto good = indexClusterPage(mPage, kPageSize);
    ASSERT_TRUE(good.isOk());
    const PositionGrid grid = testGrid();
    int refused = 0;
    constexpr int kTrials = 2000;
    for (int trial = 0; trial < kTrials; ++trial) {
        std::vector<std::byte> bytes = mPage;
        for (int f = 0; f < 1 + static_cast<int>(random() % 3); ++f)
            bytes[random() % good->usedBytes] ^= static_cast<std::byte>(1u << (random() % 8));
        const auto index = indexClusterPage(bytes, kPageSize);
        if (!index.isOk()) {
            ++refused;
            continue;
        }
        // What indexes decodes into exactly what the index says, or is refused (ASan/UBSan).
        std::vector<PackedVertex> vertices(index->vertexCount);
        std::vector<std::uint8_t> indices(index->indexCount);
        if (!decodeClusterPage(bytes, *index, grid, vertices, indices).isOk())
            ++refused;
    }
    EXPECT_GT(refused, 0);
    EXPECT_LT(refused, kTrials);
}

} // namespace
} // namespace ff::storage
