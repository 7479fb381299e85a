#include "TestScene.h"

#include <ff/storage/SceneFile.h>
#include <ff/storage/SceneWriter.h>

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <thread>
#include <vector>

namespace ff::storage {
namespace {

using test::TestScene;

constexpr std::uint32_t kSmallPage = 4096;

class SceneFileTest : public ::testing::Test {
protected:
    void SetUp() override {
        mDir = test::freshTestDir();
        mPath = mDir / "scene.ffs";
    }

    /** Writes the test scene (after `tweak`) and returns its bytes. */
    std::vector<std::byte>
    writeScene(std::uint32_t pageSize, const std::function<void(TestScene&)>& tweak = {}) {
        mScene = test::makeTestScene(pageSize);
        if (tweak)
            tweak(mScene);
        test::writeTestScene(mPath, mScene);
        return test::readBytes(mPath);
    }

    std::unique_ptr<SceneFile> openOk(const SceneFileOptions& options = {}) {
        auto file = SceneFile::open(mPath, options);
        EXPECT_TRUE(file.isOk()) << file.status().toString();
        return file.isOk() ? std::move(file).value() : nullptr;
    }

    /** Opens mPath, expecting a failure with `code` whose message starts with `prefix`. */
    void expectOpenFails(ErrorCode code, const std::string& prefix) {
        const auto file = SceneFile::open(mPath);
        ASSERT_FALSE(file.isOk()) << "opened although it should fail with '" << prefix << "'";
        EXPECT_EQ(file.status().code(), code) << file.status().toString();
        EXPECT_TRUE(test::startsWith(file.status().message(), prefix))
                << "message: " << file.status().message() << "\nexpected prefix: " << prefix;
    }

    std::filesystem::path mDir;
    std::filesystem::path mPath;
    TestScene mScene;
};

bool sameBytes(const void* a, const void* b, std::size_t n) {
    return std::memcmp(a, b, n) == 0;
}

// ---- round trip ---------------------------------------------------------------------------

class SceneFileRoundTripTest : public SceneFileTest,
                               public ::testing::WithParamInterface<std::uint32_t> {};

TEST_P(SceneFileRoundTripTest, ReadsBackEverythingWritten) {
    const std::uint32_t pageSize = GetParam();
    const std::vector<std::byte> bytes = writeScene(pageSize);
    ASSERT_EQ(bytes.size(), TestScene::kPageCount * pageSize);
    auto file = openOk();
    ASSERT_TRUE(file);

    EXPECT_EQ(file->pageSize(), pageSize);
    EXPECT_EQ(file->pageCount(), TestScene::kPageCount);
    EXPECT_EQ(file->path(), mPath);
    const FileHeader& h = file->header();
    EXPECT_EQ(h.magic, kFileMagic);
    EXPECT_EQ(h.formatVersion, kFormatVersion);
    EXPECT_EQ(h.root, TestScene::kRoot);
    EXPECT_EQ(h.nodeCount, 6u);
    EXPECT_EQ(h.storedTriangles, std::uint64_t{mScene.trianglesPerPage} * 3);
    EXPECT_EQ(h.boundsMax[2], 8.0f);
    ASSERT_EQ(file->sections().size(), 4u);
    EXPECT_EQ(file->sections()[3].type, static_cast<std::uint32_t>(SectionType::Hierarchy));

    ASSERT_EQ(file->prototypes().size(), mScene.prototypes.size());
    EXPECT_TRUE(sameBytes(
            file->prototypes().data(),
            mScene.prototypes.data(),
            mScene.prototypes.size() * sizeof(PrototypeRecord)));
    ASSERT_EQ(file->instances().size(), mScene.instances.size());
    EXPECT_TRUE(sameBytes(
            file->instances().data(),
            mScene.instances.data(),
            mScene.instances.size() * sizeof(InstanceRecord)));
    EXPECT_EQ(file->metadataJson(), mScene.metadata);
    EXPECT_GT(file->metadataJson().size(), pagePayloadBytes(pageSize));

    // Every node, through node() and child().
    for (std::uint32_t i = 0; i < mScene.nodesA.size(); ++i) {
        const auto n = file->node({TestScene::kNodePageA, i});
        ASSERT_TRUE(n.isOk()) << n.status().toString();
        EXPECT_TRUE(sameBytes(&*n, &mScene.nodesA[i], sizeof(NodeRecord))) << "slot " << i;
    }
    const auto root = file->node(h.root);
    ASSERT_TRUE(root.isOk());
    const auto child0 = file->child(*root, 0);
    ASSERT_TRUE(child0.isOk()) << child0.status().toString();
    for (std::uint32_t i = 0; i < 2; ++i) {
        const auto leaf = file->child(*child0, i);
        ASSERT_TRUE(leaf.isOk()) << leaf.status().toString();
        EXPECT_TRUE(sameBytes(&*leaf, &mScene.nodesB[i], sizeof(NodeRecord)));
    }
    EXPECT_EQ(SceneFile::childRef(*child0, 1), (NodeRef{TestScene::kNodePageB, 1}));

    // child0's triangles: three runs, continuing at slot 0 of the following pages.
    std::vector<GeometrySegment> segments;
    ASSERT_TRUE(file->geometrySegments(*child0, segments).isOk());
    const std::uint32_t t = mScene.trianglesPerPage;
    ASSERT_EQ(segments.size(), 3u);
    EXPECT_EQ(segments[0].page, 3u);
    EXPECT_EQ(segments[0].firstSlot, t - 8);
    EXPECT_EQ(segments[0].count, 8u);
    EXPECT_EQ(segments[1].page, 4u);
    EXPECT_EQ(segments[1].firstSlot, 0u);
    EXPECT_EQ(segments[1].count, t);
    EXPECT_EQ(segments[2].page, 5u);
    EXPECT_EQ(segments[2].firstSlot, 0u);
    EXPECT_EQ(segments[2].count, 24u);
    std::uint64_t checked = 0;
    for (const GeometrySegment& s : segments) {
        const auto span = file->segmentBytes(s);
        ASSERT_TRUE(span.isOk()) << span.status().toString();
        ASSERT_EQ(span->size(), std::size_t{s.count} * sizeof(PackedTriangle));
        for (std::uint32_t k = 0; k < s.count; ++k) {
            PackedTriangle got{};
            std::memcpy(&got, span->data() + k * sizeof(PackedTriangle), sizeof(got));
            const PackedTriangle want = test::makeTriangle(s.page, s.firstSlot + k);
            ASSERT_TRUE(sameBytes(&got, &want, sizeof(got)))
                    << "page " << s.page << " slot " << s.firstSlot + k;
            ++checked;
        }
    }
    EXPECT_EQ(checked, child0->geometryCount);

    // The instance node has no triangles of its own; geometrySegments appends (never clears).
    const auto instanceNode = file->child(*root, 1);
    ASSERT_TRUE(instanceNode.isOk());
    EXPECT_EQ(instanceNode->kind, static_cast<std::uint8_t>(NodeKind::Instance));
    ASSERT_TRUE(file->geometrySegments(*instanceNode, segments).isOk());
    EXPECT_EQ(segments.size(), 3u);
    const auto child2 = file->child(*root, 2);
    ASSERT_TRUE(child2.isOk());
    ASSERT_TRUE(file->geometrySegments(*child2, segments).isOk());
    ASSERT_EQ(segments.size(), 4u);
    EXPECT_EQ(segments[3].page, 3u);
    EXPECT_EQ(segments[3].firstSlot, 0u);
    EXPECT_EQ(segments[3].count, 5u);

    EXPECT_TRUE(file->verifyAll().isOk());
    auto verified = SceneFile::open(mPath, SceneFileOptions{.verifyEveryPage = true});
    EXPECT_TRUE(verified.isOk()) << verified.status().toString();
}

INSTANTIATE_TEST_SUITE_P(
        PageSizes,
        SceneFileRoundTripTest,
        ::testing::Values(kSmallPage, 65536u),
        [](const ::testing::TestParamInfo<std::uint32_t>& param) {
            return "Page" + std::to_string(param.param);
        });

TEST_F(SceneFileTest, InstanceRecordStraddlingAPageBoundaryIsReassembled) {
    writeScene(kSmallPage);
    const std::size_t payload = pagePayloadBytes(kSmallPage);
    ASSERT_NE(payload % sizeof(InstanceRecord), 0u) << "the layout no longer straddles";
    const std::size_t straddling = payload / sizeof(InstanceRecord);
    auto file = openOk();
    ASSERT_TRUE(file);
    ASSERT_GT(file->instances().size(), straddling);
    EXPECT_TRUE(sameBytes(
            &file->instances()[straddling], &mScene.instances[straddling], sizeof(InstanceRecord)));
    EXPECT_EQ(file->instances()[straddling].transform[11], static_cast<float>(straddling) + 2.75f);
}

TEST_F(SceneFileTest, FileWithoutSectionsOpensEmpty) {
    {
        auto writer = SceneWriter::create(mPath, {.pageSize = kSmallPage});
        ASSERT_TRUE(writer.isOk());
        ASSERT_TRUE((*writer)->commit(FileHeader{}, {}).isOk());
    }
    auto file = openOk();
    ASSERT_TRUE(file);
    EXPECT_EQ(file->pageCount(), 1u);
    EXPECT_TRUE(file->sections().empty());
    EXPECT_TRUE(file->prototypes().empty());
    EXPECT_TRUE(file->instances().empty());
    EXPECT_TRUE(file->metadataJson().empty());
    EXPECT_TRUE(file->verifyAll().isOk());
    // The null root points at the header page, which is never a Nodes page.
    const auto root = file->node(file->header().root);
    ASSERT_FALSE(root.isOk());
    EXPECT_EQ(root.status().message(), "page 0: expected a Nodes page, found Header (type 1)");
}

TEST_F(SceneFileTest, VerifyAllReportsProgressUpToThePageCount) {
    writeScene(kSmallPage);
    auto file = openOk();
    ASSERT_TRUE(file);
    std::vector<std::pair<std::uint64_t, std::uint64_t>> calls;
    ASSERT_TRUE(file->verifyAll([&](std::uint64_t done, std::uint64_t total) {
                        calls.emplace_back(done, total);
                    }).isOk());
    ASSERT_GE(calls.size(), 2u);
    EXPECT_EQ(calls.front(), std::make_pair(std::uint64_t{0}, TestScene::kPageCount));
    EXPECT_EQ(calls.back(), std::make_pair(TestScene::kPageCount, TestScene::kPageCount));
    for (std::size_t i = 1; i < calls.size(); ++i)
        EXPECT_LT(calls[i - 1].first, calls[i].first);
}

TEST_F(SceneFileTest, PagePayloadChecksTheExpectedType) {
    writeScene(kSmallPage);
    auto file = openOk();
    ASSERT_TRUE(file);
    const auto payload = file->pagePayload(TestScene::kNodePageA, PageType::Nodes);
    ASSERT_TRUE(payload.isOk());
    EXPECT_EQ(payload->size(), pagePayloadBytes(kSmallPage));
    EXPECT_TRUE(file->verifyPage(TestScene::kFirstGeometryPage, PageType::Geometry).isOk());
    const Status wrong = file->verifyPage(TestScene::kFirstGeometryPage, PageType::Nodes);
    EXPECT_EQ(wrong.code(), ErrorCode::Corrupt);
    EXPECT_EQ(wrong.message(), "page 3: expected a Nodes page, found Geometry (type 3)");
    // The cached verification does not turn the wrong type into a pass.
    EXPECT_FALSE(file->verifyPage(TestScene::kFirstGeometryPage, PageType::Nodes).isOk());
    const Status beyond = file->verifyPage(TestScene::kPageCount, PageType::Nodes);
    EXPECT_EQ(beyond.message(), "page 11: beyond end of file (the file has 11 pages)");
}

TEST_F(SceneFileTest, ConcurrentReadersAgree) {
    writeScene(kSmallPage);
    auto file = openOk();
    ASSERT_TRUE(file);
    std::atomic<int> failures{0};
    std::vector<std::thread> threads;
    for (int t = 0; t < 4; ++t) {
        threads.emplace_back([&file, &failures] {
            for (int round = 0; round < 20; ++round) {
                for (std::uint32_t slot = 0; slot < 4; ++slot) {
                    if (!file->node({TestScene::kNodePageA, slot}).isOk())
                        ++failures;
                }
                if (!file->verifyAll().isOk())
                    ++failures;
            }
        });
    }
    for (std::thread& t : threads)
        t.join();
    EXPECT_EQ(failures.load(), 0);
}

// ---- corruption ---------------------------------------------------------------------------

TEST_F(SceneFileTest, FlippedByteInAnyPageIsReportedWithThatPage) {
    const std::vector<std::byte> good = writeScene(kSmallPage);
    const std::size_t p = kSmallPage;
    // Payload start, middle, and every trailer field (index, type, magic, checksum).
    const std::size_t offsets[] = {0, 8, 13, 100, p / 2, p - 16, p - 12, p - 10, p - 1};
    for (std::uint64_t page = 0; page < TestScene::kPageCount; ++page) {
        for (std::size_t offset : offsets) {
            SCOPED_TRACE("page " + std::to_string(page) + " offset " + std::to_string(offset));
            std::vector<std::byte> bad = good;
            bad[page * p + offset] ^= std::byte{0x5A};
            test::writeBytes(mPath, bad);
            const std::string prefix = "page " + std::to_string(page) + ": ";

            auto file = SceneFile::open(mPath);
            if (page == 0 || page >= TestScene::kPrototypePage) {
                // Header and table pages are read by open().
                ASSERT_FALSE(file.isOk());
                EXPECT_TRUE(test::startsWith(file.status().message(), prefix))
                        << file.status().message();
                // Byte 8 of page 0 is the format version, read before anything else.
                EXPECT_EQ(
                        file.status().code(),
                        page == 0 && offset == 8 ? ErrorCode::Unsupported : ErrorCode::Corrupt);
                continue;
            }
            ASSERT_TRUE(file.isOk()) << file.status().toString();
            const Status all = (*file)->verifyAll();
            ASSERT_FALSE(all.isOk());
            EXPECT_EQ(all.code(), ErrorCode::Corrupt);
            EXPECT_TRUE(test::startsWith(all.message(), prefix)) << all.message();

            const auto eager = SceneFile::open(mPath, SceneFileOptions{.verifyEveryPage = true});
            ASSERT_FALSE(eager.isOk());
            EXPECT_TRUE(test::startsWith(eager.status().message(), prefix))
                    << eager.status().message();

            if (mScene.isNodePage(page)) {
                const auto n = (*file)->node({static_cast<std::uint32_t>(page), 0});
                ASSERT_FALSE(n.isOk());
                EXPECT_TRUE(test::startsWith(n.status().message(), prefix));
            } else {
                ASSERT_TRUE(mScene.isGeometryPage(page));
                const auto span = (*file)->segmentBytes({page, 0, 1});
                ASSERT_FALSE(span.isOk());
                EXPECT_TRUE(test::startsWith(span.status().message(), prefix));
                // Pages around it still read.
                EXPECT_TRUE((*file)->node(TestScene::kRoot).isOk());
            }
        }
    }
}

TEST_F(SceneFileTest, ChecksumMismatchMessage) {
    std::vector<std::byte> bad = writeScene(kSmallPage);
    bad[4 * kSmallPage + 7] ^= std::byte{1};
    test::writeBytes(mPath, bad);
    auto file = openOk();
    ASSERT_TRUE(file);
    const Status s = (*file).verifyAll();
    EXPECT_TRUE(test::startsWith(s.message(), "page 4: checksum mismatch (stored 0x"))
            << s.message();
}

TEST_F(SceneFileTest, PageCopiedToTheWrongPlaceIsDetected) {
    // A valid Geometry page at the index of another Geometry page: checksum fine, index wrong.
    std::vector<std::byte> bad = writeScene(kSmallPage);
    std::memcpy(&bad[4 * kSmallPage], &bad[3 * kSmallPage], kSmallPage);
    test::writeBytes(mPath, bad);
    auto file = openOk();
    ASSERT_TRUE(file);
    const auto span = file->segmentBytes({4, 0, 1});
    ASSERT_FALSE(span.isOk());
    EXPECT_EQ(
            span.status().message(),
            "page 4: trailer names page 3 (page written to the wrong place)");
}

// ---- truncation ---------------------------------------------------------------------------

TEST_F(SceneFileTest, TruncationAtEveryPageBoundaryFailsNamingTheFirstMissingPage) {
    const std::vector<std::byte> good = writeScene(kSmallPage);
    const std::size_t p = kSmallPage;
    std::vector<std::size_t> sizes;
    for (std::size_t k = 0; k < TestScene::kPageCount; ++k) {
        sizes.push_back(k * p);
        sizes.push_back(k * p + 1);
        sizes.push_back(k * p + p / 2);
        sizes.push_back(k * p + p - 1);
    }
    for (std::size_t size : sizes) {
        SCOPED_TRACE("size " + std::to_string(size));
        test::writeBytes(mPath, good, size);
        expectOpenFails(
                ErrorCode::Corrupt,
                "page " + std::to_string(size / p) + ": beyond end of file (file truncated to " +
                        std::to_string(size) + " bytes");
    }
}

TEST_F(SceneFileTest, EveryPrefixOfTheHeaderPageFailsCleanly) {
    const std::vector<std::byte> good = writeScene(kSmallPage);
    for (std::size_t size = 0; size < kSmallPage; ++size) {
        test::writeBytes(mPath, good, size);
        const auto file = SceneFile::open(mPath);
        ASSERT_FALSE(file.isOk()) << size;
        ASSERT_EQ(file.status().code(), ErrorCode::Corrupt) << size;
        ASSERT_EQ(
                file.status().message(),
                "page 0: beyond end of file (file truncated to " + std::to_string(size) +
                        " bytes)");
    }
}

TEST_F(SceneFileTest, BytesPastTheLastPageAreRejected) {
    std::vector<std::byte> bytes = writeScene(kSmallPage);
    bytes.resize(bytes.size() + kSmallPage);
    test::writeBytes(mPath, bytes);
    expectOpenFails(ErrorCode::Corrupt, "page 11: 4096 bytes past the last page");
    bytes.resize(TestScene::kPageCount * kSmallPage + 3);
    test::writeBytes(mPath, bytes);
    expectOpenFails(ErrorCode::Corrupt, "page 11: 3 bytes past the last page");
}

// ---- header -------------------------------------------------------------------------------

TEST_F(SceneFileTest, BadMagicIsRejected) {
    std::vector<std::byte> bytes = writeScene(kSmallPage);
    bytes[3] = std::byte{'X'};
    test::resealPage(bytes, kSmallPage, 0);
    test::writeBytes(mPath, bytes);
    expectOpenFails(ErrorCode::Corrupt, "page 0: bad magic (not a farfield scene file)");
    // Not a scene file at all, shorter than a header.
    const std::string text = "hello, world";
    std::vector<std::byte> textBytes(text.size());
    std::memcpy(textBytes.data(), text.data(), text.size());
    test::writeBytes(mPath, textBytes);
    expectOpenFails(ErrorCode::Corrupt, "page 0: bad magic");
}

TEST_F(SceneFileTest, OtherFormatVersionsAreUnsupported) {
    const std::vector<std::byte> good = writeScene(kSmallPage);
    for (std::uint32_t version : {0u, 3u, 0xFFFFFFFFu}) {
        std::vector<std::byte> bytes = good;
        test::storeAt<std::uint32_t>(bytes, 8, version);
        test::writeBytes(mPath, bytes); // not resealed: the version is read before the checksum
        expectOpenFails(
                ErrorCode::Unsupported,
                "page 0: format version " + std::to_string(version) + " is not supported");
    }
}

TEST_F(SceneFileTest, HeaderFieldsAreChecked) {
    const std::vector<std::byte> good = writeScene(kSmallPage);
    struct Case {
        std::size_t offset;
        std::uint64_t value;
        std::size_t width;
        ErrorCode code;
        std::string prefix;
    };
    const Case cases[] = {
            {12, 4097, 4, ErrorCode::Corrupt, "page 0: invalid page size 4097"},
            {12, 2048, 4, ErrorCode::Corrupt, "page 0: invalid page size 2048"},
            {16, 0, 8, ErrorCode::Corrupt, "page 0: page count 0 out of range"},
            {16,
             (std::uint64_t{1} << 32) + 1,
             8,
             ErrorCode::Corrupt,
             "page 0: page count 4294967297 out of range"},
            {16, 12, 8, ErrorCode::Corrupt, "page 11: beyond end of file"},
            {16, 10, 8, ErrorCode::Corrupt, "page 10: 4096 bytes past the last page"},
            {24, 144, 4, ErrorCode::Corrupt, "page 0: headerSize is 144, version 1 has 160"},
            {32, 100, 4, ErrorCode::Corrupt, "page 0: nodeRecordSize is 100, version 1 has 96"},
            {44, 57, 4, ErrorCode::Corrupt, "page 0: instanceRecordSize is 57"},
            {48, 99, 4, ErrorCode::Corrupt, "page 0: 99 sections, page 0 holds at most 98"},
            {52, 1, 4, ErrorCode::Unsupported, "page 0: unknown header flags 0x1"},
            {56, 11, 4, ErrorCode::Corrupt, "page 0: root node (page 11, slot 0) outside"},
            {60, 42, 4, ErrorCode::Corrupt, "page 0: root node (page 1, slot 42) outside"},
            {120, 0x7FF8000000000000ull, 8, ErrorCode::Corrupt, "page 0: the file frame's origin is not finite"},
            {112, 0x7FF0000000000000ull, 8, ErrorCode::Corrupt, "page 0: the file frame's origin is not finite"},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.prefix);
        std::vector<std::byte> bytes = good;
        if (c.width == 4)
            test::storeAt(bytes, c.offset, static_cast<std::uint32_t>(c.value));
        else
            test::storeAt(bytes, c.offset, c.value);
        test::resealPage(bytes, kSmallPage, 0);
        test::writeBytes(mPath, bytes);
        expectOpenFails(c.code, c.prefix);
    }
}

TEST_F(SceneFileTest, SectionTableIsChecked) {
    const std::vector<std::byte> good = writeScene(kSmallPage);
    // Section i's entry starts at 160 + 40 * i: type +0, firstPage +8, pageCount +16,
    // byteLength +24, itemCount +32. Sections: 0 Prototypes, 1 Instances, 2 Metadata, 3 Hierarchy.
    struct Case {
        std::size_t offset;
        std::uint64_t value;
        std::size_t width;
        std::string prefix;
    };
    const Case cases[] = {
            {160, 9, 4, "page 0: section 0 (unknown): unknown section type 9"},
            {160 + 40, 1, 4, "page 0: section 1 (Prototypes): duplicate section type"},
            {160 + 8, 0, 8, "page 0: section 0 (Prototypes): pages [0, +1) outside"},
            {160 + 40 + 8, 10, 8, "page 0: section 1 (Instances): pages [10, +2) outside"},
            {160 + 40 + 16, 5, 8, "page 0: section 1 (Instances): pages [7, +5) outside"},
            {160 + 40 + 16,
             3,
             8,
             "page 0: section 1 (Instances): 4144 bytes need 2 pages, the "
             "entry says 3"},
            {160 + 40 + 24, 8200, 8, "page 0: section 1 (Instances): 8200 bytes need 3 pages"},
            {160 + 40 + 32, 5, 8, "page 0: section 1 (Instances): 4144 bytes do not hold 5"},
            {160 + 80 + 8, 6, 8, "page 0: section 2 (Metadata): pages overlap section 0"},
            {160 + 120 + 24, 1, 8, "page 0: section 3 (Hierarchy): byte length 1"},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.prefix);
        std::vector<std::byte> bytes = good;
        if (c.width == 4)
            test::storeAt(bytes, c.offset, static_cast<std::uint32_t>(c.value));
        else
            test::storeAt(bytes, c.offset, c.value);
        test::resealPage(bytes, kSmallPage, 0);
        test::writeBytes(mPath, bytes);
        expectOpenFails(ErrorCode::Corrupt, c.prefix);
    }
}

TEST_F(SceneFileTest, InstanceReferringToAMissingPrototypeIsRejected) {
    writeScene(kSmallPage, [](TestScene& s) { s.instances.back().prototype = 3; });
    const std::size_t last = mScene.instances.size() - 1;
    expectOpenFails(
            ErrorCode::Corrupt,
            "page 8: instance " + std::to_string(last) + " refers to prototype 3, the file has 3");
}

TEST_F(SceneFileTest, PrototypeRootOutsideTheFileIsRejected) {
    writeScene(kSmallPage, [](TestScene& s) { s.prototypes[1].root = {99, 0}; });
    expectOpenFails(ErrorCode::Corrupt, "page 6: prototype 1: root node (page 99, slot 0)");
}

TEST_F(SceneFileTest, MissingFileIsNotFound) {
    const auto file = SceneFile::open(mDir / "absent.ffs");
    ASSERT_FALSE(file.isOk());
    EXPECT_EQ(file.status().code(), ErrorCode::NotFound);
    EXPECT_NE(file.status().message().find("absent.ffs"), std::string::npos);
}

TEST_F(SceneFileTest, DirectoryIsNotAScene) {
    const auto file = SceneFile::open(mDir);
    ASSERT_FALSE(file.isOk());
    EXPECT_EQ(file.status().code(), ErrorCode::InvalidArgument);
}

// ---- nodes --------------------------------------------------------------------------------

TEST_F(SceneFileTest, NodeRejectsOutOfRangeRefs) {
    writeScene(kSmallPage);
    auto file = openOk();
    ASSERT_TRUE(file);
    const std::uint32_t n = nodesPerPage(kSmallPage);
    struct Case {
        NodeRef ref;
        std::string message;
    };
    const Case cases[] = {
            {{1, n}, "page 1: node slot 42 out of range (a Nodes page holds 42)"},
            {{1, 0xFFFFFFFFu}, "page 1: node slot 4294967295 out of range"},
            {{11, 0}, "page 11: beyond end of file (the file has 11 pages)"},
            {{0xFFFFFFFFu, 0}, "page 4294967295: beyond end of file"},
            {{0, 0}, "page 0: expected a Nodes page, found Header (type 1)"},
            {{3, 0}, "page 3: expected a Nodes page, found Geometry (type 3)"},
            {{7, 0}, "page 7: expected a Nodes page, found Table (type 4)"},
    };
    for (const Case& c : cases) {
        const auto node = file->node(c.ref);
        ASSERT_FALSE(node.isOk()) << c.message;
        EXPECT_EQ(node.status().code(), ErrorCode::Corrupt);
        EXPECT_TRUE(test::startsWith(node.status().message(), c.message))
                << node.status().message();
    }
    // Slots past the written records are zero: a valid empty cell.
    EXPECT_TRUE(file->node({1, n - 1}).isOk());

    const auto root = file->node(TestScene::kRoot);
    ASSERT_TRUE(root.isOk());
    const auto child = file->child(*root, 3);
    ASSERT_FALSE(child.isOk());
    EXPECT_EQ(child.status().code(), ErrorCode::InvalidArgument);
}

struct MalformedNodeCase {
    const char* name;
    std::function<void(TestScene&, NodeRecord&)> mutate;
    std::string message; ///< expected prefix of the node() error for slot 1 of page 1
};

// Names the case in ctest output instead of dumping its bytes.
void PrintTo(const MalformedNodeCase& c, std::ostream* os) {
    *os << c.name;
}

class MalformedNodeTest : public SceneFileTest,
                          public ::testing::WithParamInterface<MalformedNodeCase> {};

TEST_P(MalformedNodeTest, NodeRejectsIt) {
    const MalformedNodeCase& c = GetParam();
    writeScene(kSmallPage, [&c](TestScene& s) { c.mutate(s, s.nodesA[1]); });
    auto file = openOk();
    ASSERT_TRUE(file);
    const auto node = file->node({TestScene::kNodePageA, 1});
    ASSERT_FALSE(node.isOk());
    EXPECT_EQ(node.status().code(), ErrorCode::Corrupt);
    EXPECT_TRUE(test::startsWith(node.status().message(), c.message)) << node.status().message();
    // Its siblings are fine: the error is about this record only.
    EXPECT_TRUE(file->node({TestScene::kNodePageA, 2}).isOk());
    // geometrySegments applies the same range rules to a record it is handed directly.
    NodeRecord raw = mScene.nodesA[1];
    std::vector<GeometrySegment> segments;
    const Status s = file->geometrySegments(raw, segments);
    if (!s.isOk()) {
        EXPECT_TRUE(test::startsWith(s.message(), "page ")) << s.message();
        EXPECT_TRUE(segments.empty());
    }
}

const std::uint32_t kT = trianglesPerPage(kSmallPage); // 68
const std::uint32_t kN = nodesPerPage(kSmallPage);     // 42

INSTANTIATE_TEST_SUITE_P(
        Records,
        MalformedNodeTest,
        ::testing::Values(
                MalformedNodeCase{
                        "ChildrenCrossThePageEnd",
                        [](TestScene&, NodeRecord& n) {
                            n.firstChild = {2, kN - 1};
                        },
                        "page 1: node slot 1: children in slots [41, 43) cross the end of Nodes "
                        "page 2 (42 slots)"},
                MalformedNodeCase{
                        "ChildrenSlotPastThePage",
                        [](TestScene&, NodeRecord& n) {
                            n.firstChild = {2, kN};
                        },
                        "page 1: node slot 1: children in slots [42, 44) cross the end"},
                MalformedNodeCase{
                        "ChildrenPageOutsideTheFile",
                        [](TestScene&, NodeRecord& n) {
                            n.firstChild = {11, 0};
                        },
                        "page 1: node slot 1: children on page 11, outside the file (11 pages)"},
                MalformedNodeCase{
                        "ChildrenOnTheHeaderPage",
                        [](TestScene&, NodeRecord& n) {
                            n.firstChild = {0, 0};
                        },
                        "page 1: node slot 1: children on page 0"},
                MalformedNodeCase{
                        "GeometryPastTheEndOfTheFile",
                        [](TestScene&, NodeRecord& n) { n.geometryCount = kT * 8; },
                        "page 1: node slot 1: geometry run of 544 triangles from page 3 slot 60: "
                        "ends on page 11, past the end of the file (11 pages)"},
                MalformedNodeCase{
                        "GeometryCountAtTheLimit",
                        [](TestScene&, NodeRecord& n) { n.geometryCount = 0xFFFFFFFFu; },
                        "page 1: node slot 1: geometry run of 4294967295 triangles"},
                MalformedNodeCase{
                        "GeometryPageOutsideTheFile",
                        [](TestScene&, NodeRecord& n) { n.geometryPage = 11; },
                        "page 1: node slot 1: geometry run of 100 triangles from page 11 slot 60: "
                        "page outside the file"},
                MalformedNodeCase{
                        "GeometrySlotOutOfRange",
                        [](TestScene&, NodeRecord& n) { n.geometryFirst = kT; },
                        "page 1: node slot 1: geometry run of 100 triangles from page 3 slot 68: "
                        "slot out of range (a Geometry page holds 68)"},
                MalformedNodeCase{
                        "InstanceIndexOutOfRange",
                        [](TestScene& s, NodeRecord& n) {
                            n.kind = static_cast<std::uint8_t>(NodeKind::Instance);
                            n.geometryPage = static_cast<std::uint32_t>(s.instances.size());
                        },
                        "page 1: node slot 1: instance index 74 out of range (the file has 74 "
                        "instances)"},
                MalformedNodeCase{
                        "UnknownKind",
                        [](TestScene&, NodeRecord& n) { n.kind = 2; },
                        "page 1: node slot 1: unknown node kind 2"},
                MalformedNodeCase{
                        "UnknownFlags",
                        [](TestScene&, NodeRecord& n) { n.flags = 0x80; },
                        "page 1: node slot 1: unknown node flags 0x80"},
                MalformedNodeCase{
                        "NaNBounds",
                        [](TestScene&, NodeRecord& n) {
                            n.boundsMin[1] = std::numeric_limits<float>::quiet_NaN();
                        },
                        "page 1: node slot 1: non-finite bounds"},
                MalformedNodeCase{
                        "InfiniteCell",
                        [](TestScene&, NodeRecord& n) {
                            n.cellMax[2] = std::numeric_limits<float>::infinity();
                        },
                        "page 1: node slot 1: non-finite bounds"},
                MalformedNodeCase{
                        "InvertedBounds",
                        [](TestScene&, NodeRecord& n) { n.boundsMin[0] = 5.0f; },
                        "page 1: node slot 1: bounds with min > max"}),
        [](const ::testing::TestParamInfo<MalformedNodeCase>& param) {
            return std::string(param.param.name);
        });

// ---- geometry -----------------------------------------------------------------------------

TEST_F(SceneFileTest, SegmentBytesChecksTheSegment) {
    writeScene(kSmallPage);
    auto file = openOk();
    ASSERT_TRUE(file);
    const std::uint32_t t = trianglesPerPage(kSmallPage);
    const GeometrySegment bad[] = {{3, 0, 0}, {3, t, 1}, {3, t - 1, 2}, {3, 1, 0xFFFFFFFFu}};
    for (const GeometrySegment& s : bad) {
        const auto span = file->segmentBytes(s);
        ASSERT_FALSE(span.isOk());
        EXPECT_EQ(span.status().code(), ErrorCode::InvalidArgument);
        EXPECT_TRUE(test::startsWith(span.status().message(), "page 3: segment slots"));
    }
    const auto onNodes = file->segmentBytes({1, 0, 1});
    ASSERT_FALSE(onNodes.isOk());
    EXPECT_EQ(onNodes.status().message(), "page 1: expected a Geometry page, found Nodes (type 2)");
    const auto beyond = file->segmentBytes({11, 0, 1});
    ASSERT_FALSE(beyond.isOk());
    EXPECT_TRUE(test::startsWith(beyond.status().message(), "page 11: beyond end of file"));
    const auto whole = file->segmentBytes({5, 0, t});
    ASSERT_TRUE(whole.isOk());
    EXPECT_EQ(whole->size(), std::size_t{t} * sizeof(PackedTriangle));
}

TEST_F(SceneFileTest, GeometryRunEndingOnTheLastSlotOfAPageSplitsCleanly) {
    // child0 starts at slot T-8 of page 3; T*2+8 triangles end at the last slot of page 5.
    writeScene(kSmallPage, [](TestScene& s) {
        s.nodesA[1].geometryCount = s.trianglesPerPage * 2 + 8;
    });
    auto file = openOk();
    ASSERT_TRUE(file);
    const auto node = file->node({TestScene::kNodePageA, 1});
    ASSERT_TRUE(node.isOk()) << node.status().toString();
    std::vector<GeometrySegment> segments;
    ASSERT_TRUE(file->geometrySegments(*node, segments).isOk());
    ASSERT_EQ(segments.size(), 3u);
    EXPECT_EQ(segments[2].count, trianglesPerPage(kSmallPage));
}

} // namespace
} // namespace ff::storage
