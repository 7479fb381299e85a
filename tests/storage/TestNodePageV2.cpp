// Format 2's Nodes pages (records from the front, representations from the back), its index
// (NodePages section, version-2 struct sizes, roots as node indices) and table sections that
// share pages.

#include "MemoryPageSource.h"
#include "TestScene.h"

#include <ff/storage/NodePageV2.h>
#include <ff/storage/PrototypeRecordV2.h>
#include <ff/storage/SceneFile.h>
#include <ff/storage/SceneIndex.h>
#include <ff/storage/SceneWriter.h>

#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <string>
#include <vector>

namespace ff::storage {
namespace {

using test::freshTestDir;
using test::readBytes;
using test::startsWith;

constexpr std::uint32_t kPage = kMinPageSize;
const NodeBox kUnit{{0.0f, 0.0f, 0.0f}, {1.0f, 1.0f, 1.0f}};

NodeV2 cellIn(float lo, float hi) {
    NodeV2 node;
    node.bounds = {{lo, lo, lo}, {hi, hi, hi}};
    node.flags = kNodeV2HasCube;
    node.cube[0] = {10, 20, 30, 255};
    return node;
}

RepresentationRecord clustersAt(std::uint32_t page, std::uint32_t offset) {
    RepresentationRecord r;
    r.count = 2;
    r.page = page;
    r.offset = offset;
    r.length = 100;
    return r;
}

TEST(NodePageV2Test, RecordsAndRepresentationsRoundTrip) {
    NodePageV2Writer page(kPage);
    const std::vector<RepresentationRecord> first = {clustersAt(3, 16), clustersAt(4, 16)};
    const std::vector<RepresentationRecord> second = {clustersAt(5, 200)};
    ASSERT_EQ(page.append(cellIn(0.0f, 0.5f), kUnit, first).value(), 0u);
    ASSERT_EQ(page.append(cellIn(0.25f, 1.0f), kUnit, second).value(), 1u);
    NodeV2 instance = cellIn(0.0f, 1.0f);
    instance.kind = NodeKindV2::Instance;
    instance.firstRepresentation = 7; // the instance index
    ASSERT_EQ(page.append(instance, kUnit, {}).value(), 2u);
    EXPECT_EQ(page.representationCount(), 3u);

    const auto bytes = page.bytes();
    std::vector<RepresentationRecord> reps;
    Result<NodeV2> a = readNodeV2(bytes, 9, 0, kUnit);
    ASSERT_TRUE(a.isOk()) << a.status().toString();
    ASSERT_TRUE(readRepresentationsV2(bytes, 9, *a, reps).isOk());
    EXPECT_EQ(reps, first);
    reps.clear();
    Result<NodeV2> b = readNodeV2(bytes, 9, 1, kUnit);
    ASSERT_TRUE(b.isOk());
    ASSERT_TRUE(readRepresentationsV2(bytes, 9, *b, reps).isOk());
    EXPECT_EQ(reps, second);
    EXPECT_EQ(b->cube[0], (std::array<std::uint8_t, 4>{10, 20, 30, 255}));
    Result<NodeV2> c = readNodeV2(bytes, 9, 2, kUnit);
    ASSERT_TRUE(c.isOk());
    EXPECT_EQ(c->kind, NodeKindV2::Instance);
    EXPECT_EQ(c->firstRepresentation, 7u);
    // The bounds decode outward: they hold the node.
    EXPECT_LE(a->bounds.min[0], 0.0f);
    EXPECT_GE(a->bounds.max[0], 0.5f);
}

TEST(NodePageV2Test, APageFillsWithRecordsAndRepresentationsTogether) {
    NodePageV2Writer page(kPage);
    const std::uint32_t payload = pagePayloadBytes(kPage);
    // 48 bytes a node, 20 a representation: with one each, 68 bytes a node.
    std::uint32_t appended = 0;
    while (page.fits(1, 1)) {
        ASSERT_TRUE(page.append(cellIn(0.0f, 1.0f), kUnit, std::vector{clustersAt(1, 16)}).isOk());
        ++appended;
    }
    EXPECT_EQ(appended, payload / 68);
    EXPECT_FALSE(page.append(cellIn(0.0f, 1.0f), kUnit, std::vector{clustersAt(1, 16)}).isOk());
    // Every record still reads, with its own representation.
    for (std::uint32_t s = 0; s < appended; ++s) {
        Result<NodeV2> node = readNodeV2(page.bytes(), 1, s, kUnit);
        ASSERT_TRUE(node.isOk()) << s;
        EXPECT_EQ(node->firstRepresentation, s);
    }
}

TEST(NodePageV2Test, RepresentationsReachingIntoTheSlotsAreRefused) {
    NodePageV2Writer page(kPage);
    ASSERT_TRUE(page.append(cellIn(0.0f, 1.0f), kUnit, std::vector{clustersAt(1, 16)}).isOk());
    std::vector<std::byte> bytes(page.bytes().begin(), page.bytes().end());
    // firstRepresentation (offset 40) so large that the run would end inside slot 0.
    const std::uint32_t huge = (pagePayloadBytes(kPage) - 40) / 20;
    std::memcpy(bytes.data() + 40, &huge, sizeof(huge));
    Result<NodeV2> node = readNodeV2(bytes, 4, 0, kUnit);
    ASSERT_FALSE(node.isOk());
    EXPECT_TRUE(startsWith(node.status().message(), "page 4: node slot 0: representations"))
            << node.status().message();
}

TEST(NodePageV2Test, EveryPrefixAndFlipIsReadSafely) {
    NodePageV2Writer page(kPage);
    for (int i = 0; i < 20; ++i)
        ASSERT_TRUE(page.append(cellIn(0.0f, 0.5f),
                                kUnit,
                                std::vector{clustersAt(1, 16), clustersAt(2, 16)})
                            .isOk());
    const std::vector<std::byte> good(page.bytes().begin(), page.bytes().end());
    for (std::size_t n = 0; n <= good.size(); n += 7) {
        const std::span<const std::byte> prefix(good.data(), n);
        for (std::uint32_t slot = 0; slot < 21; ++slot) {
            Result<NodeV2> node = readNodeV2(prefix, 1, slot, kUnit);
            std::vector<RepresentationRecord> reps;
            if (node)
                (void)readRepresentationsV2(prefix, 1, *node, reps); // bounded by the prefix
        }
    }
    std::mt19937_64 random(3);
    for (int trial = 0; trial < 2000; ++trial) {
        std::vector<std::byte> bytes = good;
        bytes[random() % bytes.size()] ^=
                std::byte{static_cast<unsigned char>(1u << (random() % 8))};
        const auto slot = static_cast<std::uint32_t>(random() % 21);
        Result<NodeV2> node = readNodeV2(bytes, 1, slot, kUnit);
        std::vector<RepresentationRecord> reps;
        if (node)
            (void)readRepresentationsV2(bytes, 1, *node, reps);
    }
}

/** A version 2 file: one node page, one prototype whose root is node `root`, its NodePages
 *  section listing `nodePages`, small table sections sharing pages. */
std::filesystem::path writeV2File(
        const std::filesystem::path& dir,
        std::uint32_t root,
        std::vector<std::uint32_t> nodePages = {}) {
    const std::filesystem::path path = dir / "v2.ffs";
    auto writer = SceneWriter::create(path, {.pageSize = kPage, .formatVersion = kFormatVersion2});
    EXPECT_TRUE(writer.isOk()) << writer.status().toString();
    NodePageV2Writer nodes(kPage);
    EXPECT_TRUE(nodes.append(cellIn(0.0f, 1.0f), kUnit, {}).isOk());
    const std::uint64_t nodePage = (*writer)->appendPage(PageType::Nodes, nodes.bytes()).value();
    if (nodePages.empty())
        nodePages = {static_cast<std::uint32_t>(nodePage)};
    PrototypeV2 prototype;
    prototype.rootNode = root;
    prototype.bounds = kUnit;
    prototype.grid = PositionGrid::covering(kUnit.min, kUnit.max).value();
    prototype.nodeCount = 1;
    std::vector<std::byte> protoBytes(kPrototypeRecordV2Size);
    EXPECT_TRUE(encodePrototypeV2(prototype, protoBytes).isOk());
    const std::string metadata(5000, 'm'); // longer than a 4 KiB page: the streams straddle
    const std::vector<SceneWriter::SectionStream> streams = {
            {SectionType::Prototypes, protoBytes, 1},
            {SectionType::Metadata, std::as_bytes(std::span(metadata)), 1},
            {SectionType::NodePages, std::as_bytes(std::span(nodePages)), nodePages.size()},
    };
    const std::uint64_t tableStart = (*writer)->nextPageIndex();
    auto sections = (*writer)->appendSections(streams);
    EXPECT_TRUE(sections.isOk()) << sections.status().toString();
    EXPECT_EQ((*writer)->nextPageIndex() - tableStart, 2u); // 64 + 5000 + 4 bytes: two pages
    SectionEntry hierarchy{};
    hierarchy.type = static_cast<std::uint32_t>(SectionType::Hierarchy);
    hierarchy.firstPage = 1;
    hierarchy.pageCount = tableStart - 1;
    sections->push_back(hierarchy);
    FileHeader header{};
    header.boundsMin = kUnit.min;
    header.boundsMax = kUnit.max;
    header.nodeCount = 1;
    EXPECT_TRUE((*writer)->commit(header, *sections).isOk());
    return path;
}

TEST(SceneIndexV2Test, SharedTablePagesAndTheNodeTableReadBack) {
    const auto dir = freshTestDir();
    auto file = SceneFile::open(writeV2File(dir, 0), {.verifyEveryPage = true});
    ASSERT_TRUE(file.isOk()) << file.status().toString();
    EXPECT_EQ((*file)->formatVersion(), kFormatVersion2);
    EXPECT_EQ((*file)->header().nodeRecordSize, 48u);
    EXPECT_EQ((*file)->header().prototypeRecordSize, 64u);
    ASSERT_EQ((*file)->prototypesV2().size(), 1u);
    EXPECT_TRUE((*file)->prototypes().empty());
    EXPECT_EQ((*file)->metadataJson(), std::string(5000, 'm'));
    ASSERT_EQ((*file)->nodePages().size(), 1u);
    EXPECT_EQ((*file)->nodeSlotCount(), nodesPerPageV2(kPage));
    const NodeRef root = (*file)->nodeLocation(0).value();
    EXPECT_EQ(root.page, (*file)->nodePages()[0]);
    EXPECT_EQ(root.slot, 0u);
    EXPECT_FALSE((*file)->nodeLocation(nodesPerPageV2(kPage)).isOk());
    // A version 1 reader's entry points say what to use instead.
    EXPECT_EQ(
            (*file)->decodeNode((*file)->pagePayload(root.page, PageType::Nodes).value(), root)
                    .status()
                    .code(),
            ErrorCode::Unsupported);

    // The same bytes through another source.
    auto source = test::MemoryPageSource::open(readBytes(dir / "v2.ffs"));
    ASSERT_TRUE(source.isOk());
    Result<SceneIndex> index = SceneIndex::read(**source);
    ASSERT_TRUE(index.isOk()) << index.status().toString();
    EXPECT_EQ(index->metadataJson().size(), 5000u);
}

TEST(SceneIndexV2Test, RootsOutsideTheNodeSlotsAndBadNodeTablesAreRefused) {
    const auto dir = freshTestDir();
    auto outside = SceneFile::open(writeV2File(dir, nodesPerPageV2(kPage)));
    ASSERT_FALSE(outside.isOk());
    EXPECT_NE(outside.status().message().find("root node"), std::string::npos)
            << outside.status().message();

    auto header = SceneFile::open(writeV2File(dir, 0, {0}));
    ASSERT_FALSE(header.isOk());
    EXPECT_NE(header.status().message().find("not one that can hold nodes"), std::string::npos)
            << header.status().message();

    auto twice = SceneFile::open(writeV2File(dir, 0, {1, 1}));
    ASSERT_FALSE(twice.isOk());
    EXPECT_NE(twice.status().message().find("out of order"), std::string::npos)
            << twice.status().message();
}

TEST(SceneIndexV2Test, VersionOneStructSizesInAVersionTwoHeaderAreRefused) {
    const auto dir = freshTestDir();
    std::vector<std::byte> bytes = readBytes(writeV2File(dir, 0));
    test::storeAt<std::uint32_t>(bytes, offsetof(FileHeader, nodeRecordSize), 96);
    test::resealPage(bytes, kPage, 0);
    test::writeBytes(dir / "bad.ffs", bytes);
    auto file = SceneFile::open(dir / "bad.ffs");
    ASSERT_FALSE(file.isOk());
    EXPECT_EQ(file.status().message(), "page 0: nodeRecordSize is 96, version 2 has 48");
}

TEST(SceneIndexV2Test, AStreamLengthThatWouldWrapIsRefused) {
    // With an offset, offset + byteLength could wrap to a small page count: refused first.
    const auto dir = freshTestDir();
    std::vector<std::byte> bytes = readBytes(writeV2File(dir, 0));
    const FileHeader header = test::loadAt<FileHeader>(bytes, 0);
    bool changed = false;
    for (std::uint32_t i = 0; i < header.sectionCount; ++i) {
        const std::size_t at = sizeof(FileHeader) + i * sizeof(SectionEntry);
        SectionEntry entry = test::loadAt<SectionEntry>(bytes, at);
        if (static_cast<SectionType>(entry.type) != SectionType::Metadata)
            continue;
        ASSERT_GT(entry.offset, 0u);               // after the prototype record
        entry.byteLength = ~std::uint64_t{0} - 10; // offset + this wraps past 2^64
        test::storeAt(bytes, at, entry);
        changed = true;
    }
    ASSERT_TRUE(changed);
    test::resealPage(bytes, kPage, 0);
    test::writeBytes(dir / "bad.ffs", bytes);
    auto file = SceneFile::open(dir / "bad.ffs");
    ASSERT_FALSE(file.isOk());
    EXPECT_EQ(file.status().code(), ErrorCode::Corrupt);
    EXPECT_NE(file.status().message().find("larger than the file"), std::string::npos)
            << file.status().message();
}

} // namespace
} // namespace ff::storage
