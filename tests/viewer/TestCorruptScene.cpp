// Damaged scene files through the CLI: `farfield check` names the bad page, `farfield render`
// refuses with a message naming a page, and neither ever dies of a signal. Every page is hit.

#include "FarfieldProcess.h"

#include <ff/storage/SceneFile.h>
#include <ff/storage/SceneFormat.h>

#include <xxhash.h>

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <optional>
#include <regex>
#include <set>
#include <string>
#include <vector>

namespace ff::viewer::test {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

constexpr std::size_t kPageSize = 4096;

/** Every page number that `text` mentions as "page N". */
std::set<std::uint64_t> pagesNamed(const std::string& text) {
    std::set<std::uint64_t> pages;
    static const std::regex kPage("page ([0-9]+)");
    for (auto it = std::sregex_iterator(text.begin(), text.end(), kPage);
         it != std::sregex_iterator();
         ++it)
        pages.insert(std::stoull((*it)[1].str()));
    return pages;
}

/** A small scene with many 4 KiB pages of every type: 3 sphere prototypes, 16 instances. */
fs::path buildSmallScene(const fs::path& dir, json& report) {
    const fs::path scene = dir / "scene.ffs";
    const ProcessResult built = runFarfield(
            {"build",
             "-q",
             "--generate",
             "molecule:spheres=16,triangles_per_sphere=300",
             "--page-size",
             "4KiB",
             "--format", // format 1: many pages of every type (issue 16: until ported)
             "1",
             "-o",
             scene.string(),
             "--report",
             (dir / "report.json").string()},
            dir);
    EXPECT_TRUE(built.exited && built.exitCode == 0) << built.describe();
    report = readJsonFile(dir / "report.json");
    return scene;
}

/** Runs check and render on `file`; both must exit 1 cleanly, naming `page` (if given). */
void expectRefused(const fs::path& file, const fs::path& dir, std::optional<std::uint64_t> page) {
    const ProcessResult checked = runFarfield({"check", file.string()}, dir);
    ASSERT_FALSE(checked.signaled) << checked.describe();
    EXPECT_TRUE(checked.exited && checked.exitCode == 1) << checked.describe();
    EXPECT_EQ(checked.err.rfind("farfield check: ", 0), 0u) << checked.describe();
    if (page)
        EXPECT_EQ(pagesNamed(checked.err), std::set<std::uint64_t>{*page}) << checked.describe();
    else
        EXPECT_EQ(pagesNamed(checked.err).size(), 1u) << checked.describe();

    // Every page must be read to draw ε = 0 with the whole scene in view.
    const ProcessResult rendered =
            runFarfield({"render", file.string(), "--size", "32x24", "--epsilon", "0"}, dir);
    ASSERT_FALSE(rendered.signaled) << rendered.describe();
    EXPECT_TRUE(rendered.exited && rendered.exitCode == 1) << rendered.describe();
    EXPECT_EQ(rendered.err.rfind("farfield render: ", 0), 0u) << rendered.describe();
    if (page)
        EXPECT_EQ(pagesNamed(rendered.err), std::set<std::uint64_t>{*page}) << rendered.describe();
    else
        EXPECT_NE(rendered.err.find("page"), std::string::npos) << rendered.describe();
}

TEST(CorruptSceneTest, OneFlippedByteInAnyPageIsNamed) {
    const fs::path dir = freshTestDir();
    json report;
    const fs::path scene = buildSmallScene(dir, report);
    const std::vector<unsigned char> original = readBytes(scene);
    ASSERT_EQ(original.size() % kPageSize, 0u);
    const std::size_t pageCount = original.size() / kPageSize;
    ASSERT_GE(pageCount, 20u);
    ASSERT_TRUE(report.is_object());
    EXPECT_GE(report.at("pages").at("nodes").get<std::uint64_t>(), 3u);
    EXPECT_GE(report.at("pages").at("geometry").get<std::uint64_t>(), 10u);
    EXPECT_EQ(report.at("pages").at("tables").get<std::uint64_t>(), 3u);

    const ProcessResult intact = runFarfield({"check", scene.string()}, dir);
    ASSERT_TRUE(intact.exited && intact.exitCode == 0) << intact.describe();

    const fs::path corrupt = dir / "corrupt.ffs";
    for (std::size_t page = 0; page < pageCount; ++page) {
        SCOPED_TRACE("byte flipped in page " + std::to_string(page));
        std::vector<unsigned char> bytes = original;
        bytes[page * kPageSize + kPageSize / 2] ^= 0x5A; // mid-payload (the trailer is the last 16)
        writeBytes(corrupt, bytes);
        expectRefused(corrupt, dir, page);
    }
}

TEST(CorruptSceneTest, TruncationAtEveryPageBoundaryIsRefused) {
    const fs::path dir = freshTestDir();
    json report;
    const fs::path scene = buildSmallScene(dir, report);
    const std::vector<unsigned char> original = readBytes(scene);
    const std::size_t pageCount = original.size() / kPageSize;
    ASSERT_GE(pageCount, 20u);

    const fs::path truncated = dir / "truncated.ffs";
    std::vector<std::size_t> sizes;
    for (std::size_t page = 0; page < pageCount; ++page)
        sizes.push_back(page * kPageSize);
    sizes.push_back(pageCount / 2 * kPageSize + kPageSize / 3); // mid-page
    sizes.push_back(original.size() - 1);
    for (const std::size_t size : sizes) {
        SCOPED_TRACE("truncated to " + std::to_string(size) + " bytes");
        writeBytes(
                truncated,
                std::vector<unsigned char>(
                        original.begin(), original.begin() + static_cast<std::ptrdiff_t>(size)));
        // The first page not wholly present is named; an empty or headerless file is page 0.
        expectRefused(truncated, dir, size / kPageSize);
    }
    // One page too many is refused as well.
    std::vector<unsigned char> longer = original;
    longer.resize(original.size() + kPageSize, 0);
    writeBytes(truncated, longer);
    expectRefused(truncated, dir, pageCount);
}

} // namespace
} // namespace ff::viewer::test

namespace ff::viewer::test {
namespace {

// A node that is its own child passes every per-record check (its children lie inside one
// page) and carries a valid checksum once resealed: only the traversal can notice the cycle.
TEST(CorruptSceneTest, AReferenceCycleIsReportedNotFollowedForever) {
    const fs::path dir = freshTestDir();
    const fs::path scene = dir / "scene.ffs";
    const ProcessResult built = runFarfield(
            {"build", "-q", "--generate", "forest:trees=4", "--page-size", "4KiB", "--format", "1", // until ported
             "-o", scene.string()},
            dir);
    ASSERT_EQ(built.exitCode, 0) << built.describe();
    storage::NodeRef root{};
    {
        const auto file = storage::SceneFile::open(scene);
        ASSERT_TRUE(file.isOk()) << file.status().toString();
        root = (*file)->prototypes().at(0).root;
    }
    std::vector<unsigned char> bytes = readBytes(scene);
    const std::size_t page = std::size_t{root.page} * kPageSize;
    storage::NodeRecord record{};
    std::memcpy(&record, bytes.data() + page + std::size_t{root.slot} * sizeof(record), sizeof(record));
    ASSERT_GT(record.childCount, 0);
    record.firstChild = root;
    record.childCount = 1;
    std::memcpy(bytes.data() + page + std::size_t{root.slot} * sizeof(record), &record, sizeof(record));
    const std::uint64_t checksum = XXH3_64bits(bytes.data() + page, kPageSize - 8);
    std::memcpy(bytes.data() + page + kPageSize - 8, &checksum, sizeof(checksum));
    const fs::path cyclic = dir / "cyclic.ffs";
    writeBytes(cyclic, bytes);

    const ProcessResult checked = runFarfield({"check", cyclic.string()}, dir);
    EXPECT_EQ(checked.exitCode, 0) << checked.describe(); // every page is intact
    for (const char* method : {"hierarchical", "full"}) {
        const ProcessResult rendered = runFarfield(
                {"render", cyclic.string(), "--method", method, "--distance", "0.6", "--size", "64x48", "-o",
                 (dir / "out.png").string()},
                dir);
        EXPECT_FALSE(rendered.signaled) << rendered.describe();
        EXPECT_EQ(rendered.exitCode, 1) << rendered.describe();
        EXPECT_NE(rendered.err.find("reference cycle"), std::string::npos) << rendered.err;
    }
}

} // namespace
} // namespace ff::viewer::test
