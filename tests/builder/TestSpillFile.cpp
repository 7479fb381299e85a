// SpillFile: the builder's temporary streams (run files, level files).

#include "RunFile.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <string>
#include <sys/stat.h>
#include <vector>

namespace ff::builder {
namespace {

namespace fs = std::filesystem;

fs::path freshTestDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    const fs::path dir = fs::path(FF_TEST_TMP_DIR) / (std::string(info->test_suite_name()) + "." + info->name());
    std::error_code ec;
    fs::remove_all(dir, ec);
    fs::create_directories(dir);
    return dir;
}

storage::NodeRecord recordNumbered(std::uint32_t n) {
    storage::NodeRecord r{};
    r.geometryCount = n;
    return r;
}

/** Bytes the file system holds for `path` (its blocks, not its size). */
std::uint64_t allocatedBytes(const fs::path& path) {
    struct stat st{};
    EXPECT_EQ(::stat(path.c_str(), &st), 0);
    return static_cast<std::uint64_t>(st.st_blocks) * 512;
}

// A pass that moves every item elsewhere (the distribute pass over a run file) should not need
// their disk space twice: the file gives its space back behind the reader, and is gone after.
// (Holes are punched with fallocate; the build directories here and in CI are on ext4/overlay,
// which support it.)
TEST(SpillFileTest, ConsumingTheFileGivesItsSpaceBackAsItGoes) {
    const fs::path dir = freshTestDir();
    RecordFile file(dir / "run.nodes");
    constexpr std::uint32_t kRecords = (8u << 20) / sizeof(storage::NodeRecord);
    std::vector<storage::NodeRecord> records;
    for (std::uint32_t i = 0; i < kRecords; ++i)
        records.push_back(recordNumbered(i));
    ASSERT_TRUE(file.append(records).isOk());
    ASSERT_TRUE(file.flush().isOk());
    const std::uint64_t size = kRecords * sizeof(storage::NodeRecord);
    ASSERT_GE(allocatedBytes(file.path()), size);

    std::uint32_t next = 0;
    std::uint64_t allocatedNearTheEnd = 0;
    const Result<std::uint64_t> released = file.consumeBatches(
            (1u << 20) / sizeof(storage::NodeRecord),
            [&](std::span<const storage::NodeRecord> batch) {
                for (const storage::NodeRecord& r : batch)
                    EXPECT_EQ(r.geometryCount, next++);
                if (next == kRecords) // by the last batch, all but the last ~2 MiB is given back
                    allocatedNearTheEnd = allocatedBytes(file.path());
                return Status::ok();
            });
    ASSERT_TRUE(released.isOk()) << released.status().toString();
    EXPECT_EQ(next, kRecords);
    EXPECT_GE(*released, size - (2u << 20));
    EXPECT_LE(allocatedNearTheEnd, 3u << 20) << "of " << size << " bytes";
    EXPECT_FALSE(fs::exists(file.path()));
    EXPECT_EQ(file.count(), 0u);
}

// Small appends are gathered in the buffer, large ones go straight to the file; either way the
// file reads back as everything appended, in order, and the bytes written are counted.
TEST(SpillFileTest, BufferedAndWrittenThroughAppendsReadBackInOrder) {
    const fs::path dir = freshTestDir();
    RecordFile file(dir / "level.nodes");
    file.setBufferLimit(10 * sizeof(storage::NodeRecord));
    std::vector<storage::NodeRecord> expected;
    std::uint32_t next = 0;
    for (const std::size_t count : {3u, 4u, 25u, 1u, 0u, 9u, 40u, 2u}) {
        std::vector<storage::NodeRecord> batch;
        for (std::size_t i = 0; i < count; ++i)
            batch.push_back(recordNumbered(next++));
        ASSERT_TRUE(file.append(batch).isOk());
        expected.insert(expected.end(), batch.begin(), batch.end());
    }
    EXPECT_EQ(file.count(), expected.size());
    EXPECT_LT(file.bufferedBytes(), 10 * sizeof(storage::NodeRecord));
    std::vector<std::uint32_t> read;
    ASSERT_TRUE(file.forEachBatch(7, [&](std::span<const storage::NodeRecord> batch) {
                        EXPECT_LE(batch.size(), 7u);
                        for (const storage::NodeRecord& r : batch)
                            read.push_back(r.geometryCount);
                        return Status::ok();
                    }).isOk());
    std::vector<std::uint32_t> want(expected.size());
    std::transform(expected.begin(), expected.end(), want.begin(), [](const storage::NodeRecord& r) {
        return r.geometryCount;
    });
    EXPECT_EQ(read, want);
    EXPECT_EQ(file.bytesWritten(), expected.size() * sizeof(storage::NodeRecord));
    EXPECT_EQ(fs::file_size(dir / "level.nodes"), expected.size() * sizeof(storage::NodeRecord));

    file.remove();
    EXPECT_FALSE(fs::exists(dir / "level.nodes"));
}

// A full disk is reported as DiskFull, with the file's name, on the append that writes.
TEST(SpillFileTest, FullDiskIsReportedOnTheAppendThatWrites) {
    if (!fs::exists("/dev/full"))
        GTEST_SKIP() << "no /dev/full";
    const fs::path dir = freshTestDir();
    const fs::path path = dir / "level.run";
    fs::create_symlink("/dev/full", path); // every write fails with ENOSPC, as on a full disk
    RunFile file(path);
    file.setBufferLimit(0);
    const std::vector<storage::PackedTriangle> triangles(16);
    const Status status = file.append(triangles);
    EXPECT_EQ(status.code(), ErrorCode::DiskFull) << status.toString();
    EXPECT_NE(status.message().find(path.string()), std::string::npos) << status.message();
}

} // namespace
} // namespace ff::builder
