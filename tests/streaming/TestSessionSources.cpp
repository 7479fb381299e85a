// A whole streaming session over a page source that is not a file: the scene index and every
// page come through IPageSource, so a range server or object storage needs a source, not a
// rewrite. The scene's bytes are served from memory after the file is gone.

#include "MemoryPageSource.h"
#include "TestDir.h"

#include <ff/builder/Generators.h>
#include <ff/builder/SceneBuilder.h>
#include <ff/runtime/CameraOptions.h>
#include <ff/runtime/OffscreenContext.h>
#include <ff/runtime/StreamingSession.h>
#include <ff/storage/SceneFile.h>

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>
#include <vector>

namespace ff::runtime {
namespace {

namespace fs = std::filesystem;

constexpr std::uint64_t kCacheBytes = 4ull << 20;

fs::path buildTerrain(const fs::path& file) {
    builder::BuildOptions options;
    options.memoryBudgetBytes = builder::SceneBuilder::kMinimumBudgetBytes;
    // Format 1 until this test is ported to format 2 (issue 16: version 1 is to be refused).
    options.formatVersion = storage::kFormatVersion;
    options.pageSize = 16u << 10; // several pages per level: the cut streams in over frames
    auto scene = builder::SceneBuilder::create(file, options);
    EXPECT_TRUE(scene.isOk()) << scene.status().toString();
    auto spec = builder::parseGeneratorSpec("terrain:triangles=20000");
    EXPECT_TRUE(spec.isOk());
    EXPECT_TRUE(builder::runGenerator(*spec, **scene).isOk());
    auto report = (*scene)->finish();
    EXPECT_TRUE(report.isOk()) << report.status().toString();
    return file;
}

std::vector<std::byte> readAll(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    const std::vector<char> chars(
            (std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::vector<std::byte> bytes(chars.size());
    std::memcpy(bytes.data(), chars.data(), chars.size());
    return bytes;
}

class SessionSourcesTest : public ::testing::Test {
protected:
    void SetUp() override {
        auto context = OffscreenContext::create();
        ASSERT_TRUE(context.isOk()) << context.status().toString();
        mContext = std::move(*context);
    }

    FrameContext frameFor(const StreamingSession& session) const {
        FrameContext frame;
        frame.width = 160;
        frame.height = 120;
        auto camera = CameraOptions{}.resolve(session.scene());
        EXPECT_TRUE(camera.isOk()) << camera.status().toString();
        frame.camera = *camera;
        frame.camera.fitClipPlanes(sceneBounds(session.scene()));
        frame.selection.epsilonPixels = 1.0f;
        return frame;
    }

    std::unique_ptr<OffscreenContext> mContext;
};

TEST_F(SessionSourcesTest, ASessionOverPagesInMemoryDrawsWhatTheFileDraws) {
    const fs::path file = buildTerrain(test::freshDir() / "terrain.ffs");
    SessionOptions options;
    options.cacheBytes = kCacheBytes;
    auto fromFile = StreamingSession::open(file, options);
    ASSERT_TRUE(fromFile.isOk()) << fromFile.status().toString();
    auto fileFrame = (*fromFile)->renderComplete(frameFor(**fromFile));
    ASSERT_TRUE(fileFrame.isOk()) << fileFrame.status().toString();

    auto memory = storage::test::MemoryPageSource::open(readAll(file));
    ASSERT_TRUE(memory.isOk()) << memory.status().toString();
    fs::remove(file); // from here on, nothing can come from the file
    std::shared_ptr<storage::test::MemoryPageSource> source(std::move(*memory));
    auto fromMemory =
            StreamingSession::open(std::shared_ptr<storage::IPageSource>(source), options);
    ASSERT_TRUE(fromMemory.isOk()) << fromMemory.status().toString();
    EXPECT_TRUE((*fromMemory)->streams());
    auto memoryFrame = (*fromMemory)->renderComplete(frameFor(**fromMemory));
    ASSERT_TRUE(memoryFrame.isOk()) << memoryFrame.status().toString();

    EXPECT_EQ(memoryFrame->image.rgba, fileFrame->image.rgba);
    EXPECT_EQ(memoryFrame->stats.trianglesDrawn, fileFrame->stats.trianglesDrawn);
    EXPECT_GT(memoryFrame->stats.trianglesDrawn, 0u);
    // The pages the frame needed came through the source, the index's too.
    const auto reads = source->reads();
    ASSERT_EQ(reads.count(0), 1u);
    EXPECT_EQ(reads.at(0), 1) << "page 0 is read once, for the index";
    const std::uint64_t root = (*fromMemory)->scene().header().root.page;
    ASSERT_EQ(reads.count(root), 1u);
    EXPECT_EQ(reads.at(root), 1) << "the root's page is read once, and stays resident";
    EXPECT_GT(reads.size(), 2u);
}

TEST_F(SessionSourcesTest, ACorruptTablePageFailsTheSessionAtOpenNamingThePage) {
    const fs::path file = buildTerrain(test::freshDir() / "terrain.ffs");
    std::vector<std::byte> bytes = readAll(file);
    std::uint64_t metadataPage = 0;
    {
        auto scene = storage::SceneFile::open(file);
        ASSERT_TRUE(scene.isOk());
        for (const storage::SectionEntry& s : (*scene)->sections()) {
            if (static_cast<storage::SectionType>(s.type) == storage::SectionType::Metadata)
                metadataPage = s.firstPage;
        }
    }
    ASSERT_GT(metadataPage, 0u);
    const std::uint32_t pageSize = 16u << 10;
    bytes[metadataPage * pageSize + 3] ^= std::byte{0x10}; // the checksum no longer matches
    auto memory = storage::test::MemoryPageSource::open(bytes);
    ASSERT_TRUE(memory.isOk()) << memory.status().toString(); // page 0 is intact
    SessionOptions options;
    options.cacheBytes = kCacheBytes;
    auto session = StreamingSession::open(
            std::shared_ptr<storage::IPageSource>(std::move(*memory)), options);
    ASSERT_FALSE(session.isOk());
    EXPECT_EQ(session.status().code(), ErrorCode::Corrupt);
    const std::string prefix = "page " + std::to_string(metadataPage) + ": checksum mismatch";
    EXPECT_EQ(session.status().message().rfind(prefix, 0), 0u) << session.status().message();
}

TEST_F(SessionSourcesTest, ABudgetBelowOnePageIsRefusedBeforeAnythingIsRead) {
    const fs::path file = buildTerrain(test::freshDir() / "terrain.ffs");
    auto memory = storage::test::MemoryPageSource::open(readAll(file));
    ASSERT_TRUE(memory.isOk());
    std::shared_ptr<storage::test::MemoryPageSource> source(std::move(*memory));
    SessionOptions options;
    options.cacheBytes = source->pageSize() - 1;
    auto session = StreamingSession::open(std::shared_ptr<storage::IPageSource>(source), options);
    ASSERT_FALSE(session.isOk());
    EXPECT_EQ(session.status().code(), ErrorCode::OutOfBudget);
    EXPECT_TRUE(source->reads().empty());
}

} // namespace
} // namespace ff::runtime
