// The cluster page packer (builder/src/ClusterPagePacker.h): a node's clusters go to the oldest
// open page they fit, so a page closes with the slack no later cluster fits, and every node's
// representations name runs that together hold all of its clusters.

#include "ClusterPagePacker.h"
#include "GeneratedTriangles.h"
#include "OctreeBuilder.h"

#include <ff/builder/ClusterBuild.h>
#include <ff/storage/ClusterPage.h>
#include <ff/storage/SceneWriter.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <limits>
#include <vector>

namespace ff::builder {
namespace {

constexpr std::uint32_t kPage = 4096;

/** One cluster of the first `count` triangles of a terrain row (a strip: few vertices). */
std::vector<std::byte> oneCluster(std::size_t count) {
    static const std::vector<storage::PackedTriangle> terrain =
            testing::generatedTriangles("terrain:triangles=20000");
    const auto strip = std::span(terrain).first(count);
    glm::vec3 lo(std::numeric_limits<float>::max());
    glm::vec3 hi(std::numeric_limits<float>::lowest());
    for (const auto& t : terrain)
        growBounds(lo, hi, t);
    const auto grid = storage::PositionGrid::covering({lo.x, lo.y, lo.z}, {hi.x, hi.y, hi.z});
    EXPECT_TRUE(grid.isOk());
    std::vector<std::byte> bytes;
    const auto stats = ClusterEncoder().encode(strip, *grid, bytes);
    EXPECT_TRUE(stats.isOk());
    EXPECT_EQ(stats.isOk() ? stats->clusters : 0u, 1u);
    return bytes;
}

bool fitTogether(std::initializer_list<const std::vector<std::byte>*> clusters) {
    storage::ClusterPageWriter page(kPage, 0);
    for (const auto* c : clusters) {
        if (!page.fits(*c, 1))
            return false;
        EXPECT_TRUE(page.append(*c, 1).isOk());
    }
    return true;
}

/** A version 2 writer of kPage pages to a temporary file, never committed (so removed). */
Result<std::unique_ptr<storage::SceneWriter>> makeWriter(const char* name) {
    return storage::SceneWriter::create(
            std::filesystem::path(FF_TEST_TMP_DIR) / name,
            {.pageSize = kPage, .formatVersion = storage::kFormatVersion2});
}

TEST(ClusterPagePackerTest, ALaterNodesClusterFillsAnOlderPage) {
    // Two nodes of three large clusters, a page each, then two nodes of one small cluster that
    // fits beside either three but not twice: with one open page the first page closes with its
    // slack and the second small cluster needs a third page; with older pages kept open, each
    // small cluster fills one of the two pages.
    const std::vector<std::byte> large = oneCluster(120);
    const std::vector<std::byte> small = oneCluster(20);
    ASSERT_TRUE(fitTogether({&large, &large, &large, &small}));
    ASSERT_FALSE(fitTogether({&large, &large, &large, &large}));
    ASSERT_FALSE(fitTogether({&large, &large, &large, &small, &small}));
    std::vector<std::byte> threeLarge;
    for (int i = 0; i < 3; ++i)
        threeLarge.insert(threeLarge.end(), large.begin(), large.end());

    auto writer = makeWriter("packer.ffs");
    ASSERT_TRUE(writer.isOk()) << writer.status().toString();
    ClusterPagePacker packer(**writer, 0);
    const std::vector<std::pair<const std::vector<std::byte>*, std::uint32_t>> payloads = {
            {&threeLarge, 3}, {&threeLarge, 3}, {&small, 1}, {&small, 1}};
    std::vector<std::vector<storage::RepresentationRecord>> nodes(payloads.size());
    for (std::size_t n = 0; n < payloads.size(); ++n)
        ASSERT_TRUE(packer.place(*payloads[n].first, payloads[n].second, nodes[n]).isOk());
    ASSERT_TRUE(packer.finish().isOk());
    EXPECT_EQ(packer.pages(), 2u);
    // Each node one run holding all its clusters; the small ones beside the large, oldest first.
    for (std::size_t n = 0; n < nodes.size(); ++n) {
        ASSERT_EQ(nodes[n].size(), 1u) << "node " << n;
        EXPECT_EQ(nodes[n][0].count, payloads[n].second);
        EXPECT_EQ(nodes[n][0].length, payloads[n].first->size());
        EXPECT_EQ(nodes[n][0].kind, storage::RepresentationKind::Clusters);
    }
    EXPECT_EQ(nodes[0][0].page, 0u);
    EXPECT_EQ(nodes[1][0].page, 1u);
    EXPECT_EQ(nodes[2][0].page, 0u);
    EXPECT_EQ(nodes[3][0].page, 1u);
}

TEST(ClusterPagePackerTest, ANodeSpreadOverPagesGetsARunInEach) {
    // Many clusters of one node: runs in consecutive pages, their counts adding up.
    std::vector<std::byte> payload;
    constexpr std::uint32_t kClusters = 12;
    for (std::uint32_t c = 0; c < kClusters; ++c) {
        const std::vector<std::byte> cluster = oneCluster(60 + 5 * c);
        payload.insert(payload.end(), cluster.begin(), cluster.end());
    }
    auto writer = makeWriter("packer-spread.ffs");
    ASSERT_TRUE(writer.isOk()) << writer.status().toString();
    ClusterPagePacker packer(**writer, 0);
    std::vector<storage::RepresentationRecord> runs;
    ASSERT_TRUE(packer.place(payload, kClusters, runs).isOk());
    ASSERT_TRUE(packer.finish().isOk());
    EXPECT_GT(runs.size(), 1u);
    EXPECT_EQ(runs.size(), packer.pages()); // one run a page it reached
    std::uint32_t clusters = 0;
    std::uint64_t bytes = 0;
    for (std::size_t r = 0; r < runs.size(); ++r) {
        EXPECT_EQ(runs[r].page, r);
        clusters += runs[r].count;
        bytes += runs[r].length;
    }
    EXPECT_EQ(clusters, kClusters);
    EXPECT_EQ(bytes, payload.size());
}

} // namespace
} // namespace ff::builder
