#include "TestScene.h"

#include <ff/storage/SceneFile.h>
#include <ff/storage/SceneWriter.h>

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>
#include <xxhash.h>

#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

namespace ff::storage {
namespace {

constexpr std::uint32_t kSmallPage = 4096;

class SceneWriterTest : public ::testing::Test {
protected:
    void SetUp() override {
        mDir = test::freshTestDir();
        mPath = mDir / "scene.ffs";
    }

    std::filesystem::path expectedTempPath() const {
        return mDir / ("scene.ffs.tmp-" + std::to_string(::getpid()));
    }

    std::unique_ptr<SceneWriter> createOk(std::uint32_t pageSize = kSmallPage) {
        auto writer = SceneWriter::create(mPath, {.pageSize = pageSize});
        EXPECT_TRUE(writer.isOk()) << writer.status().toString();
        return writer.isOk() ? std::move(writer).value() : nullptr;
    }

    std::filesystem::path mDir;
    std::filesystem::path mPath;
};

std::vector<std::byte> filled(std::size_t n, std::uint8_t value) {
    return std::vector<std::byte>(n, std::byte{value});
}

bool contains(const std::string& text, const std::string& part) {
    return text.find(part) != std::string::npos;
}

TEST_F(SceneWriterTest, RefusesInvalidPageSizes) {
    for (std::uint32_t size : {0u, 1u, 2048u, 4095u, 5000u, 12288u, 32u << 20, 0x80000000u}) {
        const auto writer = SceneWriter::create(mPath, {.pageSize = size});
        ASSERT_FALSE(writer.isOk()) << size;
        EXPECT_EQ(writer.status().code(), ErrorCode::InvalidArgument);
        EXPECT_TRUE(contains(writer.status().message(), "page size " + std::to_string(size)))
                << writer.status().message();
    }
    EXPECT_FALSE(std::filesystem::exists(expectedTempPath()));
    for (std::uint32_t size : {4096u, 8192u, 65536u, 16u << 20})
        EXPECT_TRUE(SceneWriter::create(mPath, {.pageSize = size}).isOk()) << size;
}

TEST_F(SceneWriterTest, WritesToATemporaryFileUntilCommit) {
    auto writer = createOk();
    ASSERT_TRUE(writer);
    EXPECT_EQ(writer->temporaryPath(), expectedTempPath());
    EXPECT_TRUE(std::filesystem::exists(expectedTempPath()));
    EXPECT_EQ(writer->pageSize(), kSmallPage);
    EXPECT_EQ(writer->nextPageIndex(), 1u);
    for (std::uint64_t i = 1; i <= 3; ++i) {
        const auto page = writer->appendPage(PageType::Nodes, filled(10, 1));
        ASSERT_TRUE(page.isOk());
        EXPECT_EQ(*page, i);
    }
    EXPECT_FALSE(std::filesystem::exists(mPath));
    ASSERT_TRUE(writer->commit(FileHeader{}, {}).isOk());
    EXPECT_TRUE(std::filesystem::exists(mPath));
    EXPECT_FALSE(std::filesystem::exists(expectedTempPath()));
    EXPECT_EQ(std::filesystem::file_size(mPath), 4u * kSmallPage);
}

TEST_F(SceneWriterTest, DestroyingWithoutCommitRemovesTheTemporaryFile) {
    {
        auto writer = createOk();
        ASSERT_TRUE(writer);
        // More than the write buffer, so data really reached the temporary file.
        for (int i = 0; i < 300; ++i)
            ASSERT_TRUE(writer->appendPage(PageType::Geometry, filled(100, 2)).isOk());
        EXPECT_GT(std::filesystem::file_size(expectedTempPath()), 0u);
    }
    EXPECT_FALSE(std::filesystem::exists(expectedTempPath()));
    EXPECT_FALSE(std::filesystem::exists(mPath));
}

TEST_F(SceneWriterTest, CommitReplacesAnExistingFile) {
    test::writeBytes(mPath, filled(123, 7));
    auto writer = createOk();
    ASSERT_TRUE(writer);
    ASSERT_TRUE(writer->appendPage(PageType::Nodes, {}).isOk());
    // The old file stays intact until the rename.
    EXPECT_EQ(std::filesystem::file_size(mPath), 123u);
    ASSERT_TRUE(writer->commit(FileHeader{}, {}).isOk());
    EXPECT_EQ(std::filesystem::file_size(mPath), 2u * kSmallPage);
}

TEST_F(SceneWriterTest, PageBytesFollowTheDocumentedLayout) {
    auto writer = createOk();
    ASSERT_TRUE(writer);
    std::vector<std::byte> payload(pagePayloadBytes(kSmallPage));
    for (std::size_t i = 0; i < payload.size(); ++i)
        payload[i] = static_cast<std::byte>(i * 7 + 1);
    ASSERT_TRUE(writer->appendPage(PageType::Geometry, payload).isOk());
    ASSERT_TRUE(writer->appendPage(PageType::Nodes, filled(5, 0xAB)).isOk());
    FileHeader header{};
    header.root = {2, 0};
    header.nodeCount = 1;
    header.flags = 0;
    SectionEntry hierarchy{};
    hierarchy.type = static_cast<std::uint32_t>(SectionType::Hierarchy);
    hierarchy.firstPage = 1;
    hierarchy.pageCount = 2;
    ASSERT_TRUE(writer->commit(header, std::span<const SectionEntry>(&hierarchy, 1)).isOk());

    const std::vector<std::byte> bytes = test::readBytes(mPath);
    ASSERT_EQ(bytes.size(), 3u * kSmallPage);
    // Header (FORMAT.md "Page 0").
    EXPECT_EQ(std::memcmp(bytes.data(), "FFSCENE\0", 8), 0);
    EXPECT_EQ(test::loadAt<std::uint32_t>(bytes, 8), kFormatVersion);
    EXPECT_EQ(test::loadAt<std::uint32_t>(bytes, 12), kSmallPage);
    EXPECT_EQ(test::loadAt<std::uint64_t>(bytes, 16), 3u);
    EXPECT_EQ(test::loadAt<std::uint32_t>(bytes, 24), 160u);
    EXPECT_EQ(test::loadAt<std::uint32_t>(bytes, 28), 40u);
    EXPECT_EQ(test::loadAt<std::uint32_t>(bytes, 32), 96u);
    EXPECT_EQ(test::loadAt<std::uint32_t>(bytes, 36), 60u);
    EXPECT_EQ(test::loadAt<std::uint32_t>(bytes, 40), 48u);
    EXPECT_EQ(test::loadAt<std::uint32_t>(bytes, 44), 56u);
    EXPECT_EQ(test::loadAt<std::uint32_t>(bytes, 48), 1u);  // sectionCount
    EXPECT_EQ(test::loadAt<std::uint32_t>(bytes, 56), 2u);  // root.page
    EXPECT_EQ(test::loadAt<std::uint64_t>(bytes, 88), 1u);  // nodeCount
    EXPECT_EQ(test::loadAt<std::uint32_t>(bytes, 160), 4u); // section 0 type: Hierarchy
    EXPECT_EQ(test::loadAt<std::uint64_t>(bytes, 168), 1u); // firstPage
    EXPECT_EQ(test::loadAt<std::uint64_t>(bytes, 176), 2u); // pageCount
    for (std::size_t i = 160 + 40; i < kSmallPage - 16; ++i)
        ASSERT_EQ(bytes[i], std::byte{0}) << "page 0 byte " << i;
    // Trailers (FORMAT.md "Page layout").
    const std::uint16_t types[] = {1, 3, 2};
    for (std::size_t page = 0; page < 3; ++page) {
        const std::size_t end = (page + 1) * kSmallPage;
        EXPECT_EQ(test::loadAt<std::uint32_t>(bytes, end - 16), page);
        EXPECT_EQ(test::loadAt<std::uint16_t>(bytes, end - 12), types[page]);
        EXPECT_EQ(test::loadAt<std::uint16_t>(bytes, end - 10), 0xFF5Cu);
        EXPECT_EQ(
                test::loadAt<std::uint64_t>(bytes, end - 8),
                XXH3_64bits(bytes.data() + page * kSmallPage, kSmallPage - 8));
    }
    EXPECT_EQ(std::memcmp(bytes.data() + kSmallPage, payload.data(), payload.size()), 0);
    // A short payload is followed by zeros up to the trailer.
    EXPECT_EQ(bytes[2 * kSmallPage + 4], std::byte{0xAB});
    for (std::size_t i = 5; i < pagePayloadBytes(kSmallPage); ++i)
        ASSERT_EQ(bytes[2 * kSmallPage + i], std::byte{0}) << "page 2 byte " << i;
}

TEST_F(SceneWriterTest, RejectsBadPagesAndSections) {
    auto writer = createOk();
    ASSERT_TRUE(writer);
    const auto tooBig = writer->appendPage(PageType::Nodes, filled(kSmallPage - 15, 0));
    ASSERT_FALSE(tooBig.isOk());
    EXPECT_EQ(tooBig.status().code(), ErrorCode::InvalidArgument);
    EXPECT_TRUE(writer->appendPage(PageType::Nodes, filled(kSmallPage - 16, 0)).isOk());
    const auto header = writer->appendPage(PageType::Header, {});
    ASSERT_FALSE(header.isOk());
    EXPECT_EQ(header.status().code(), ErrorCode::InvalidArgument);
    EXPECT_FALSE(writer->appendPage(static_cast<PageType>(9), {}).isOk());

    const auto mismatched = writer->appendSection(SectionType::Instances, filled(100, 0), 2);
    ASSERT_FALSE(mismatched.isOk());
    EXPECT_EQ(mismatched.status().code(), ErrorCode::InvalidArgument);
    EXPECT_FALSE(writer->appendSection(SectionType::Hierarchy, {}, 0).isOk());
    EXPECT_EQ(writer->nextPageIndex(), 2u) << "failed appends must not add pages";
    // The writer is still usable after refused arguments.
    const auto empty = writer->appendSection(SectionType::Metadata, {}, 0);
    ASSERT_TRUE(empty.isOk());
    EXPECT_EQ(empty->pageCount, 0u);
    EXPECT_EQ(empty->firstPage, 2u);
    ASSERT_TRUE(writer->commit(FileHeader{}, std::span<const SectionEntry>(&*empty, 1)).isOk());
    auto file = SceneFile::open(mPath);
    ASSERT_TRUE(file.isOk()) << file.status().toString();
    EXPECT_TRUE((*file)->metadataJson().empty());
}

TEST_F(SceneWriterTest, SectionsSplitIntoTablePages) {
    auto writer = createOk();
    ASSERT_TRUE(writer);
    const std::size_t payload = pagePayloadBytes(kSmallPage);
    const auto exact = writer->appendSection(SectionType::Metadata, filled(2 * payload, 'a'), 1);
    ASSERT_TRUE(exact.isOk());
    EXPECT_EQ(exact->firstPage, 1u);
    EXPECT_EQ(exact->pageCount, 2u);
    EXPECT_EQ(exact->byteLength, 2 * payload);
    const auto records = writer->appendSection(
            SectionType::Prototypes, filled(sizeof(PrototypeRecord) * 100, 0), 100);
    ASSERT_TRUE(records.isOk());
    EXPECT_EQ(records->firstPage, 3u);
    EXPECT_EQ(records->pageCount, 2u); // 4800 bytes
    EXPECT_EQ(records->itemCount, 100u);
    EXPECT_EQ(records->type, static_cast<std::uint32_t>(SectionType::Prototypes));
    EXPECT_EQ(writer->nextPageIndex(), 5u);
}

TEST_F(SceneWriterTest, CommitRefusesASectionTableTheReaderWouldReject) {
    auto writer = createOk();
    ASSERT_TRUE(writer);
    ASSERT_TRUE(writer->appendPage(PageType::Nodes, {}).isOk());
    SectionEntry hierarchy{};
    hierarchy.type = static_cast<std::uint32_t>(SectionType::Hierarchy);
    hierarchy.firstPage = 1;
    hierarchy.pageCount = 2; // only page 1 exists
    const Status s = writer->commit(FileHeader{}, std::span<const SectionEntry>(&hierarchy, 1));
    ASSERT_FALSE(s.isOk());
    EXPECT_EQ(s.code(), ErrorCode::InvalidArgument);
    EXPECT_TRUE(contains(s.message(), "section 0 (Hierarchy): pages [1, +2) outside"))
            << s.message();
    // Finished whatever the outcome: nothing left behind, nothing more accepted.
    EXPECT_FALSE(std::filesystem::exists(expectedTempPath()));
    EXPECT_FALSE(std::filesystem::exists(mPath));
    EXPECT_FALSE(writer->appendPage(PageType::Nodes, {}).isOk());
    EXPECT_FALSE(writer->commit(FileHeader{}, {}).isOk());
}

TEST_F(SceneWriterTest, CommitRefusesTooManySections) {
    auto writer = createOk();
    ASSERT_TRUE(writer);
    EXPECT_EQ(maxSectionCount(kSmallPage), 98u);
    EXPECT_EQ(maxSectionCount(65536), (65520u - 160u) / 40u);
    EXPECT_EQ(maxSectionCount(1000), 0u);
    const std::vector<SectionEntry> sections(99);
    const Status s = writer->commit(FileHeader{}, sections);
    EXPECT_EQ(s.code(), ErrorCode::InvalidArgument);
    EXPECT_FALSE(std::filesystem::exists(mPath));
}

TEST_F(SceneWriterTest, AppendAndCommitAfterCommitFail) {
    auto writer = createOk();
    ASSERT_TRUE(writer);
    ASSERT_TRUE(writer->commit(FileHeader{}, {}).isOk());
    const auto page = writer->appendPage(PageType::Nodes, {});
    ASSERT_FALSE(page.isOk());
    EXPECT_EQ(page.status().code(), ErrorCode::InvalidArgument);
    EXPECT_FALSE(writer->appendSection(SectionType::Metadata, filled(3, 'x'), 1).isOk());
    EXPECT_FALSE(writer->commit(FileHeader{}, {}).isOk());
    EXPECT_TRUE(std::filesystem::exists(mPath)) << "a finished writer keeps its committed file";
}

// ---- environment failures ------------------------------------------------------------------

TEST_F(SceneWriterTest, MissingOutputDirectoryIsAClearError) {
    const std::filesystem::path path = mDir / "no-such-dir" / "scene.ffs";
    const auto writer = SceneWriter::create(path);
    ASSERT_FALSE(writer.isOk());
    EXPECT_EQ(writer.status().code(), ErrorCode::NotFound);
    EXPECT_TRUE(contains(writer.status().message(), "cannot create temporary file"));
    EXPECT_TRUE(contains(writer.status().message(), path.string()));
    EXPECT_TRUE(contains(writer.status().message(), "No such file or directory"));
}

TEST_F(SceneWriterTest, OutputDirectoryThatIsAFileIsAClearError) {
    test::writeBytes(mDir / "file", filled(1, 0));
    const std::filesystem::path path = mDir / "file" / "scene.ffs";
    const auto writer = SceneWriter::create(path);
    ASSERT_FALSE(writer.isOk());
    EXPECT_EQ(writer.status().code(), ErrorCode::IoError);
    EXPECT_TRUE(contains(writer.status().message(), path.string()));
    EXPECT_TRUE(contains(writer.status().message(), "Not a directory"));
}

// sysfs refuses new files even to root (which ignores directory permission bits), so it is an
// unwritable directory on every Linux machine this runs on.
TEST_F(SceneWriterTest, UnwritableOutputDirectoryIsAClearError) {
    const auto writer = SceneWriter::create("/sys/farfield-scene.ffs");
    ASSERT_FALSE(writer.isOk());
    EXPECT_EQ(writer.status().code(), ErrorCode::IoError);
    EXPECT_TRUE(contains(writer.status().message(), "/sys/farfield-scene.ffs"));
    EXPECT_TRUE(contains(writer.status().message(), "Permission denied"));
}

TEST_F(SceneWriterTest, FinalPathThatIsADirectoryIsRefused) {
    const auto writer = SceneWriter::create(mDir);
    ASSERT_FALSE(writer.isOk());
    EXPECT_EQ(writer.status().code(), ErrorCode::InvalidArgument);
}

// The temporary file is opened by name, so a symlink at that name to /dev/full makes every
// write fail with ENOSPC, exactly as a full disk does, without root or a tiny filesystem.
class SceneWriterDiskFullTest : public SceneWriterTest {
protected:
    void SetUp() override {
        SceneWriterTest::SetUp();
        if (!std::filesystem::exists("/dev/full"))
            GTEST_SKIP() << "no /dev/full";
        std::filesystem::create_symlink("/dev/full", expectedTempPath());
    }

    void expectDiskFull(const Status& s) {
        EXPECT_EQ(s.code(), ErrorCode::DiskFull) << s.toString();
        EXPECT_TRUE(contains(s.message(), "disk full")) << s.message();
        EXPECT_TRUE(contains(s.message(), expectedTempPath().string())) << s.message();
        // The temporary name is removed at once and nothing appears under the final name.
        EXPECT_FALSE(std::filesystem::exists(std::filesystem::symlink_status(expectedTempPath())));
        EXPECT_FALSE(std::filesystem::exists(mPath));
    }
};

TEST_F(SceneWriterDiskFullTest, AppendReportsDiskFullOnceTheBufferIsWritten) {
    auto writer = createOk();
    ASSERT_TRUE(writer);
    Status failure;
    for (int i = 0; i < 1000 && failure.isOk(); ++i)
        failure = writer->appendPage(PageType::Geometry, filled(64, 3)).status();
    ASSERT_FALSE(failure.isOk()) << "1000 pages appended to /dev/full";
    expectDiskFull(failure);
    // Sticky: later calls report the same failure.
    EXPECT_EQ(writer->appendPage(PageType::Geometry, {}).status().code(), ErrorCode::DiskFull);
    EXPECT_EQ(writer->commit(FileHeader{}, {}).code(), ErrorCode::DiskFull);
}

TEST_F(SceneWriterDiskFullTest, CommitReportsDiskFull) {
    auto writer = createOk();
    ASSERT_TRUE(writer);
    ASSERT_TRUE(writer->appendPage(PageType::Nodes, filled(64, 3)).isOk()); // still buffered
    expectDiskFull(writer->commit(FileHeader{}, {}));
}

} // namespace
} // namespace ff::storage
