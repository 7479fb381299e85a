// SpillFile: the builder's temporary streams (run files, level files).

#include "RunFile.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
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
    RecordFile file(dir / "run.nodes", SpillCodec::Raw); // raw: the file is as large as its items
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

class SpillCodecTest : public ::testing::TestWithParam<SpillCodec> {};

// Small appends are gathered in the buffer, large ones go straight to the file; either way the
// file reads back as everything appended, in order, and the bytes written are counted.
TEST_P(SpillCodecTest, BufferedAndWrittenThroughAppendsReadBackInOrder) {
    const fs::path dir = freshTestDir();
    RecordFile file(dir / "level.nodes", GetParam());
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
    EXPECT_EQ(fs::file_size(dir / "level.nodes"), file.bytesWritten());
    const std::uint64_t raw = expected.size() * sizeof(storage::NodeRecord);
    if (GetParam() == SpillCodec::Raw) // the items and a 16-byte header per block
        EXPECT_GT(file.bytesWritten(), raw);
    else // records that are mostly zeros: a fraction of their size
        EXPECT_LT(file.bytesWritten(), raw / 4);

    file.remove();
    EXPECT_FALSE(fs::exists(dir / "level.nodes"));
}

/** Triangles as a terrain spills them, with the bit patterns a lossy codec would lose: NaN
 *  payloads, -0, denormals, and every byte of the colours and normals. */
std::vector<storage::PackedTriangle> awkwardTriangles(std::size_t count) {
    std::vector<storage::PackedTriangle> triangles(count);
    std::uint32_t state = 12345;
    const auto next = [&state] { return state = state * 1664525u + 1013904223u; };
    for (std::size_t i = 0; i < count; ++i) {
        for (int v = 0; v < 3; ++v) {
            storage::PackedVertex& vertex = triangles[i].vertices[static_cast<std::size_t>(v)];
            vertex.position = {static_cast<float>(i % 300) * 0.5f + static_cast<float>(v),
                               std::sin(static_cast<float>(i) * 0.01f),
                               static_cast<float>(i / 300) * 0.5f};
            vertex.normalOct = {static_cast<std::int16_t>(next()), static_cast<std::int16_t>(next())};
            const std::uint32_t colour = next();
            std::memcpy(vertex.color.data(), &colour, 4);
        }
        if (i % 97 == 0) {
            const std::uint32_t patterns[] = {0x7FC00123u, 0x80000000u, 0x00000001u};
            std::memcpy(&triangles[i].vertices[0].position[i % 3], &patterns[i % 3], 4);
        }
    }
    return triangles;
}

TEST_P(SpillCodecTest, TrianglesReadBackBitForBit) {
    const fs::path dir = freshTestDir();
    RunFile file(dir / "proto.run", GetParam());
    const std::vector<storage::PackedTriangle> triangles = awkwardTriangles(50000); // 3 MB: blocks of 1 MiB
    for (std::size_t at = 0; at < triangles.size(); at += 7000)
        ASSERT_TRUE(file.append(std::span(triangles).subspan(at, std::min<std::size_t>(7000, triangles.size() - at))).isOk());
    const auto back = file.readAll();
    ASSERT_TRUE(back.isOk()) << back.status().toString();
    ASSERT_EQ(back->size(), triangles.size());
    EXPECT_EQ(std::memcmp(back->data(), triangles.data(), triangles.size() * sizeof(storage::PackedTriangle)), 0);
}

TEST_P(SpillCodecTest, ADamagedOrShortFileIsAClearError) {
    const fs::path dir = freshTestDir();
    const fs::path path = dir / "proto.run";
    RunFile file(path, GetParam());
    ASSERT_TRUE(file.append(awkwardTriangles(30000)).isOk());
    ASSERT_TRUE(file.flush().isOk());
    const std::uint64_t size = fs::file_size(path);
    const std::vector<char> good = [&] {
        std::ifstream in(path, std::ios::binary);
        return std::vector<char>(std::istreambuf_iterator<char>(in), {});
    }();
    const auto rewrite = [&](std::vector<char> bytes) {
        std::ofstream out(path, std::ios::binary | std::ios::trunc);
        out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    };
    const auto readBack = [&] {
        return file.forEachBatch(1000, [](std::span<const storage::PackedTriangle>) { return Status::ok(); });
    };

    std::vector<char> badMagic = good;
    badMagic[0] ^= 1;
    rewrite(badMagic);
    Status status = readBack();
    EXPECT_EQ(status.code(), ErrorCode::IoError);
    EXPECT_NE(status.message().find("block at byte 0 has a bad header"), std::string::npos) << status.message();

    std::vector<char> hugeCount = good;
    hugeCount[10] = 0x7F; // item count (bytes 8-11) far beyond a block
    rewrite(hugeCount);
    status = readBack();
    EXPECT_NE(status.message().find("bad header"), std::string::npos) << status.message();

    for (const std::uint64_t cut : {size - 1, size / 2, std::uint64_t{8}}) {
        rewrite(std::vector<char>(good.begin(), good.begin() + static_cast<std::ptrdiff_t>(cut)));
        status = readBack();
        EXPECT_EQ(status.code(), ErrorCode::IoError) << cut;
        EXPECT_NE(status.message().find("shorter than written"), std::string::npos) << status.message();
    }
    rewrite(good);
    EXPECT_TRUE(readBack().isOk());
}

INSTANTIATE_TEST_SUITE_P(
        Codecs,
        SpillCodecTest,
        ::testing::Values(SpillCodec::Raw, SpillCodec::Compact),
        [](const ::testing::TestParamInfo<SpillCodec>& codec) { return std::string(spillCodecName(codec.param)); });

TEST(SpillFileTest, CompactSpillOfATerrainIsSmallerThanRaw) {
    const fs::path dir = freshTestDir();
    const std::vector<storage::PackedTriangle> triangles = awkwardTriangles(40000);
    RunFile raw(dir / "raw.run", SpillCodec::Raw);
    RunFile compact(dir / "compact.run", SpillCodec::Compact);
    ASSERT_TRUE(raw.append(triangles).isOk());
    ASSERT_TRUE(compact.append(triangles).isOk());
    ASSERT_TRUE(raw.flush().isOk());
    ASSERT_TRUE(compact.flush().isOk());
    // Random normals and colours (8 of 20 bytes a vertex) do not compress; the positions do.
    EXPECT_LT(compact.bytesWritten(), raw.bytesWritten() * 3 / 4)
            << compact.bytesWritten() << " of " << raw.bytesWritten();
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
