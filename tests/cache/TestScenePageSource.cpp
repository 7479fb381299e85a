#include "../storage/TestScene.h"

#include <ff/cache/PageCache.h>
#include <ff/cache/ScenePageSource.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cstring>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <thread>
#include <vector>

namespace ff::cache {
namespace {

using storage::test::TestScene;

constexpr std::uint32_t kPageSize = 4096;

/** Writes the storage tests' scene (11 pages of 4 KiB) and returns its path and bytes. */
struct SceneOnDisk {
    std::filesystem::path path;
    std::vector<std::byte> bytes;

    std::span<const std::byte> page(std::uint64_t index) const {
        return std::span<const std::byte>(bytes).subspan(index * kPageSize, kPageSize);
    }
};

SceneOnDisk writeScene() {
    SceneOnDisk scene;
    scene.path = storage::test::freshTestDir() / "scene.ffs";
    storage::test::writeTestScene(scene.path, storage::test::makeTestScene(kPageSize));
    scene.bytes = storage::test::readBytes(scene.path);
    EXPECT_EQ(scene.bytes.size(), TestScene::kPageCount * kPageSize);
    return scene;
}

/** Flips one payload byte of `page` on disk (the checksum no longer matches). */
void flipByte(SceneOnDisk& scene, std::uint64_t page) {
    scene.bytes[page * kPageSize + 100] ^= std::byte{0x40};
    storage::test::writeBytes(scene.path, scene.bytes);
}

std::unique_ptr<ScenePageSource> openSource(const std::filesystem::path& path) {
    auto source = ScenePageSource::open(path);
    EXPECT_TRUE(source.isOk()) << source.status().toString();
    return source.isOk() ? std::move(source).value() : nullptr;
}

bool sameBytes(std::span<const std::byte> a, std::span<const std::byte> b) {
    return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin());
}

TEST(ScenePageSourceTest, ReadsEveryPageOfASceneFile) {
    const SceneOnDisk scene = writeScene();
    auto source = openSource(scene.path);
    ASSERT_NE(source, nullptr);
    EXPECT_EQ(source->pageSize(), kPageSize);
    EXPECT_EQ(source->pageCount(), TestScene::kPageCount);
    EXPECT_EQ(source->path(), scene.path);
    std::vector<std::byte> buffer(kPageSize);
    for (std::uint64_t page = 0; page < TestScene::kPageCount; ++page) {
        const Status read = source->readPage(page, buffer);
        ASSERT_TRUE(read.isOk()) << read.toString();
        EXPECT_TRUE(sameBytes(buffer, scene.page(page))) << page;
    }
}

TEST(ScenePageSourceTest, AFlippedByteIsCorruptNamingThePage) {
    SceneOnDisk scene = writeScene();
    flipByte(scene, 4);
    auto source = openSource(scene.path); // open checks page 0 and the sections, not page 4
    ASSERT_NE(source, nullptr);
    std::vector<std::byte> buffer(kPageSize);
    const Status read = source->readPage(4, buffer);
    EXPECT_EQ(read.code(), ErrorCode::Corrupt);
    EXPECT_TRUE(storage::test::startsWith(read.message(), "page 4: checksum mismatch"))
            << read.message();
    EXPECT_TRUE(source->readPage(3, buffer).isOk());
    EXPECT_TRUE(source->readPage(5, buffer).isOk());
}

TEST(ScenePageSourceTest, APageWrittenToTheWrongPlaceIsCorrupt) {
    SceneOnDisk scene = writeScene();
    // Geometry page 3 copied over geometry page 5: intact in itself, but in the wrong place.
    std::memcpy(scene.bytes.data() + 5 * kPageSize, scene.bytes.data() + 3 * kPageSize, kPageSize);
    storage::test::writeBytes(scene.path, scene.bytes);
    auto source = openSource(scene.path);
    ASSERT_NE(source, nullptr);
    std::vector<std::byte> buffer(kPageSize);
    const Status read = source->readPage(5, buffer);
    EXPECT_EQ(read.code(), ErrorCode::Corrupt);
    EXPECT_TRUE(storage::test::startsWith(read.message(), "page 5: trailer names page 3"))
            << read.message();
}

TEST(ScenePageSourceTest, ReadsConcurrentlyFromSeveralThreads) {
    SceneOnDisk scene = writeScene();
    flipByte(scene, 4);
    std::shared_ptr<ScenePageSource> source = openSource(scene.path);
    ASSERT_NE(source, nullptr);
    constexpr int kThreads = 4;
    constexpr int kRounds = 40;
    std::atomic<int> wrongBytes{0};
    std::atomic<int> wrongStatus{0};
    const std::vector<std::byte>& expected = scene.bytes;
    std::vector<std::thread> threads;
    for (int t = 0; t < kThreads; ++t) {
        threads.emplace_back([source, t, &expected, &wrongBytes, &wrongStatus] {
            std::vector<std::byte> buffer(kPageSize);
            for (int round = 0; round < kRounds; ++round) {
                for (std::uint64_t i = 0; i < TestScene::kPageCount; ++i) {
                    // Each thread walks the pages from a different starting point.
                    const std::uint64_t page =
                            (i + static_cast<std::uint64_t>(t) * 3) % TestScene::kPageCount;
                    const Status read = source->readPage(page, buffer);
                    if (page == 4) {
                        if (read.code() != ErrorCode::Corrupt ||
                            read.message().rfind("page 4: ", 0) != 0)
                            ++wrongStatus;
                        continue;
                    }
                    if (!read.isOk())
                        ++wrongStatus;
                    else if (
                            std::memcmp(
                                    buffer.data(), expected.data() + page * kPageSize, kPageSize) !=
                            0)
                        ++wrongBytes;
                }
            }
        });
    }
    for (std::thread& thread : threads)
        thread.join();
    EXPECT_EQ(wrongStatus.load(), 0);
    EXPECT_EQ(wrongBytes.load(), 0);
}

TEST(ScenePageSourceTest, AMissingFileIsNotFound) {
    const auto source = ScenePageSource::open(storage::test::freshTestDir() / "absent.ffs");
    ASSERT_FALSE(source.isOk());
    EXPECT_EQ(source.status().code(), ErrorCode::NotFound);
    EXPECT_NE(source.status().message().find("absent.ffs"), std::string::npos);
}

TEST(ScenePageSourceTest, ACorruptHeaderFailsAtOpenNamingThePage) {
    SceneOnDisk scene = writeScene();
    flipByte(scene, 0);
    const auto source = ScenePageSource::open(scene.path);
    ASSERT_FALSE(source.isOk());
    EXPECT_EQ(source.status().code(), ErrorCode::Corrupt);
    EXPECT_TRUE(storage::test::startsWith(source.status().message(), "page 0: checksum mismatch"))
            << source.status().message();
}

TEST(ScenePageSourceTest, PagesBeyondTheEndAreCorrupt) {
    const SceneOnDisk scene = writeScene();
    auto source = openSource(scene.path);
    ASSERT_NE(source, nullptr);
    std::vector<std::byte> buffer(kPageSize);
    const Status beyond = source->readPage(TestScene::kPageCount, buffer);
    EXPECT_EQ(beyond.code(), ErrorCode::Corrupt);
    EXPECT_TRUE(storage::test::startsWith(beyond.message(), "page 11: beyond end of file"))
            << beyond.message();

    // The file shrinks under an open source.
    std::filesystem::resize_file(scene.path, 8 * kPageSize);
    const Status shrunk = source->readPage(9, buffer);
    EXPECT_EQ(shrunk.code(), ErrorCode::Corrupt);
    EXPECT_TRUE(storage::test::startsWith(shrunk.message(), "page 9: beyond end of file"))
            << shrunk.message();
    EXPECT_TRUE(source->readPage(7, buffer).isOk());
}

TEST(ScenePageSourceTest, FeedsAPageCache) {
    SceneOnDisk scene = writeScene();
    flipByte(scene, 4);
    std::shared_ptr<ScenePageSource> source = openSource(scene.path);
    ASSERT_NE(source, nullptr);
    PageCacheOptions options;
    options.budgetBytes = 8 * kPageSize;
    auto created = PageCache::create(source, options);
    ASSERT_TRUE(created.isOk()) << created.status().toString();
    PageCache& cache = **created;

    cache.beginFrame();
    for (std::uint64_t page = 1; page < 8; ++page)
        cache.request(page, static_cast<float>(page));
    cache.endFrame();
    cache.drain();
    cache.beginFrame();
    for (std::uint64_t page = 1; page < 8; ++page) {
        if (page == 4) {
            EXPECT_EQ(cache.state(page), PageState::Failed);
            const auto failure = cache.failure(page);
            ASSERT_TRUE(failure.has_value());
            EXPECT_EQ(failure->code(), ErrorCode::Corrupt);
            continue;
        }
        const auto bytes = cache.tryGet(page);
        ASSERT_TRUE(bytes.has_value()) << page;
        EXPECT_TRUE(sameBytes(*bytes, scene.page(page))) << page;
    }
    EXPECT_EQ(cache.stats().failed, 1u);
    EXPECT_EQ(cache.stats().residentBytes, 6u * kPageSize);
}

} // namespace
} // namespace ff::cache
