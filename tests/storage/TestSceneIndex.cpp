// The scene index read through a page source that is not a file: the same records as the mapped
// reader, only page 0 and the table pages read, and every prefix and bit flip of the header page
// refused with a clear error.

#include "MemoryPageSource.h"
#include "TestScene.h"

#include <ff/storage/PageSource.h>
#include <ff/storage/SceneFile.h>
#include <ff/storage/SceneIndex.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <map>
#include <random>
#include <vector>

namespace ff::storage {
namespace {

constexpr std::uint32_t kPageSize = 4096;

using BytesSource = test::MemoryPageSource;

class SceneIndexTest : public ::testing::Test {
protected:
    void SetUp() override {
        mPath = test::freshTestDir() / "scene.ffs";
        mScene = test::makeTestScene(kPageSize);
        test::writeTestScene(mPath, mScene);
        mBytes = test::readBytes(mPath);
    }

    std::filesystem::path mPath;
    test::TestScene mScene;
    std::vector<std::byte> mBytes;
};

template <typename T> bool sameBytes(const std::vector<T>& a, const std::vector<T>& b) {
    return a.size() == b.size() &&
           (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

TEST_F(SceneIndexTest, ReadThroughAnySourceItHoldsWhatTheMappedFileHolds) {
    auto source = BytesSource::open(mBytes);
    ASSERT_TRUE(source.isOk()) << source.status().toString();
    auto index = SceneIndex::read(**source);
    ASSERT_TRUE(index.isOk()) << index.status().toString();
    auto file = SceneFile::open(mPath);
    ASSERT_TRUE(file.isOk()) << file.status().toString();

    EXPECT_EQ(std::memcmp(&index->header(), &(*file)->header(), sizeof(FileHeader)), 0);
    EXPECT_TRUE(sameBytes(index->prototypes(), mScene.prototypes));
    EXPECT_TRUE(sameBytes(index->instances(), mScene.instances));
    EXPECT_EQ(index->metadataJson(), mScene.metadata);
    ASSERT_EQ(index->sections().size(), (*file)->sections().size());

    // Only the header and the table pages: node and geometry pages are the frames' business.
    std::map<std::uint64_t, int> expected{{0, 1}, {test::TestScene::kPrototypePage, 1}};
    for (std::uint64_t p = test::TestScene::kFirstInstancePage; p < test::TestScene::kPageCount;
         ++p)
        expected[p] = 1;
    EXPECT_EQ((*source)->reads(), expected);

    // Nodes decode from bytes wherever they came from: here, the source's.
    std::vector<std::byte> page(kPageSize);
    ASSERT_TRUE((*source)->readPage(test::TestScene::kNodePageA, page).isOk());
    const auto root = index->decodeNode(page, test::TestScene::kRoot);
    ASSERT_TRUE(root.isOk()) << root.status().toString();
    EXPECT_EQ(std::memcmp(&*root, &mScene.nodesA[0], sizeof(NodeRecord)), 0);
    std::vector<GeometrySegment> runs;
    ASSERT_TRUE(index->geometrySegments(mScene.nodesA[1], runs).isOk());
    EXPECT_EQ(runs.size(), 3u);
}

TEST_F(SceneIndexTest, ASourceServingAnotherLayoutIsRefused) {
    // A source that believes the pages are twice as many as the header says.
    class Lying final : public IPageSource {
    public:
        explicit Lying(IPageSource& inner)
            : mInner(inner) {}
        std::uint32_t pageSize() const override { return mInner.pageSize(); }
        std::uint64_t pageCount() const override { return 2 * mInner.pageCount(); }
        Status readPage(std::uint64_t index, std::span<std::byte> out) override {
            return mInner.readPage(index, out);
        }

    private:
        IPageSource& mInner;
    };
    auto source = BytesSource::open(mBytes);
    ASSERT_TRUE(source.isOk());
    Lying lying(**source);
    const auto index = SceneIndex::read(lying);
    ASSERT_FALSE(index.isOk());
    EXPECT_EQ(index.status().code(), ErrorCode::Corrupt);
    EXPECT_TRUE(test::startsWith(index.status().message(), "page 0: the header says 11 pages"))
            << index.status().message();
}

TEST_F(SceneIndexTest, EveryPrefixOfTheFileIsRefusedCleanly) {
    // A source learns its layout from the first bytes and the size: every shorter file fails,
    // naming the first page it lacks; none is served.
    for (std::size_t size = 0; size < mBytes.size(); size += (size < 2 * kPageSize ? 1 : 61)) {
        const std::vector<std::byte> prefix(
                mBytes.begin(), mBytes.begin() + static_cast<std::ptrdiff_t>(size));
        const auto source = BytesSource::open(prefix);
        ASSERT_FALSE(source.isOk()) << size;
        ASSERT_EQ(source.status().code(), ErrorCode::Corrupt) << size;
        const std::string expected = "page " + std::to_string(size / kPageSize) +
                                     ": beyond end of file (file truncated to " +
                                     std::to_string(size) + " bytes";
        ASSERT_TRUE(test::startsWith(source.status().message(), expected))
                << size << ": " << source.status().message();
    }
}

TEST_F(SceneIndexTest, RandomBitFlipsInTheIndexPagesAreRefusedOrHarmless) {
    // Flips anywhere in page 0 and the table pages, resealed so the checksum passes and the
    // decoders meet the garbage: each open and read is refused with a Status or succeeds with
    // checked records; none crashes (ASan/UBSan run this too).
    std::mt19937 random(1234);
    std::vector<std::uint64_t> indexPages{0, test::TestScene::kPrototypePage};
    for (std::uint64_t p = test::TestScene::kFirstInstancePage; p < test::TestScene::kPageCount;
         ++p)
        indexPages.push_back(p);
    int refused = 0;
    constexpr int kTrials = 600;
    for (int trial = 0; trial < kTrials; ++trial) {
        std::vector<std::byte> bytes = mBytes;
        const std::uint64_t page = indexPages[random() % indexPages.size()];
        const int flips = 1 + static_cast<int>(random() % 3);
        for (int f = 0; f < flips; ++f) {
            // The first 160 bytes of page 0 are the header: flipped more often, they matter most.
            const std::size_t span =
                    page == 0 && trial % 2 == 0 ? sizeof(FileHeader) : pagePayloadBytes(kPageSize);
            bytes[page * kPageSize + random() % span] ^=
                    static_cast<std::byte>(1u << (random() % 8));
        }
        test::resealPage(bytes, kPageSize, page);
        auto source = BytesSource::open(bytes);
        if (!source.isOk()) {
            ++refused;
            continue;
        }
        const auto index = SceneIndex::read(**source);
        if (!index.isOk()) {
            EXPECT_TRUE(
                    index.status().code() == ErrorCode::Corrupt ||
                    index.status().code() == ErrorCode::Unsupported)
                    << index.status().toString();
            ++refused;
            continue;
        }
        // What was accepted is consistent: every instance names a prototype that exists.
        for (const InstanceRecord& instance : index->instances())
            ASSERT_LT(instance.prototype, index->prototypes().size());
    }
    // Most flips land in checked fields or metadata text; both outcomes must occur.
    EXPECT_GT(refused, 0);
    EXPECT_LT(refused, kTrials);
}

TEST_F(SceneIndexTest, APinOwnsItsPageWhereTheSourceDoesNotMapIt) {
    auto source = BytesSource::open(mBytes);
    ASSERT_TRUE(source.isOk());
    auto pin = (*source)->pinPage(test::TestScene::kNodePageA);
    ASSERT_TRUE(pin.isOk()) << pin.status().toString();
    source->reset(); // the source goes; the pinned bytes stay
    ASSERT_EQ(pin->bytes().size(), kPageSize);
    EXPECT_EQ(
            std::memcmp(
                    pin->bytes().data(),
                    mBytes.data() + test::TestScene::kNodePageA * kPageSize,
                    kPageSize),
            0);
    PagePin moved = std::move(*pin);
    EXPECT_TRUE(pin->empty());
    EXPECT_FALSE(moved.empty());
    moved.reset();
    EXPECT_TRUE(moved.empty());
}

TEST_F(SceneIndexTest, TheMappedFilePinsAViewOfItsMapping) {
    auto file = SceneFile::open(mPath);
    ASSERT_TRUE(file.isOk());
    auto pin = (*file)->source().pinPage(test::TestScene::kFirstGeometryPage);
    ASSERT_TRUE(pin.isOk());
    const auto payload =
            (*file)->pagePayload(test::TestScene::kFirstGeometryPage, PageType::Geometry);
    ASSERT_TRUE(payload.isOk());
    EXPECT_EQ(pin->bytes().data(), payload->data()); // no copy
    // A corrupt page is refused by the pin as by every other access.
    std::vector<std::byte> bad = mBytes;
    bad[test::TestScene::kFirstGeometryPage * kPageSize + 5] ^= std::byte{1};
    test::writeBytes(mPath, bad);
    auto badFile = SceneFile::open(mPath);
    ASSERT_TRUE(badFile.isOk());
    const auto badPin = (*badFile)->source().pinPage(test::TestScene::kFirstGeometryPage);
    ASSERT_FALSE(badPin.isOk());
    EXPECT_TRUE(test::startsWith(badPin.status().message(), "page 3: checksum mismatch"));
}

} // namespace
} // namespace ff::storage
