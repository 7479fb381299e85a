// Every output path of every verb is checked before the work starts (issue 13): a missing
// folder or an image format nobody writes fails at once with the path named, prints no frame
// statistics (rendering never began), leaves no temporary file behind and never clobbers an
// existing file. A successful run replaces its outputs whole.

#include "FarfieldProcess.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

namespace ff::viewer::test {
namespace {

namespace fs = std::filesystem;

class OutputPathTest : public ::testing::Test {
protected:
    void SetUp() override {
        mDir = freshTestDir();
        mScene = mDir / "tree.ffs";
        const ProcessResult built = runFarfield(
                {"build", "-q", "--generate", "forest:trees=1", "-o", mScene.string()}, mDir);
        ASSERT_EQ(built.exitCode, 0) << built.describe();
        mPath = mDir / "orbit.json";
        const ProcessResult path = runFarfield(
                {"path", "orbit", mScene.string(), "-o", mPath.string(), "--frames", "2"}, mDir);
        ASSERT_EQ(path.exitCode, 0) << path.describe();
    }

    /** Runs `args`, which name an unwritable output `bad`: `exitCode` at once, `bad` in the
     * message, nothing on stdout (no frame was rendered), no temporary left in mDir. */
    void expectRefusedUpFront(
            const std::vector<std::string>& args, const std::string& bad, int exitCode = 1) {
        SCOPED_TRACE(args.front() + " with " + bad);
        const ProcessResult r = runFarfield(args, mDir);
        EXPECT_EQ(r.exitCode, exitCode) << r.describe();
        EXPECT_NE(r.err.find(bad.substr(0, bad.rfind('/'))), std::string::npos) << r.err;
        EXPECT_EQ(r.out.find("nodes_visited"), std::string::npos) << "the work ran: " << r.out;
        expectNoTemporaries();
    }

    void expectNoTemporaries() {
        for (const auto& entry : fs::directory_iterator(mDir))
            EXPECT_EQ(entry.path().filename().string().find(".tmp"), std::string::npos)
                    << entry.path();
    }

    fs::path mDir;
    fs::path mScene;
    fs::path mPath;
};

TEST_F(OutputPathTest, EveryVerbRefusesAMissingOutputFolderBeforeItsWork) {
    const std::string missing = (mDir / "no-such-dir" / "out").string();
    const std::string scene = mScene.string();
    expectRefusedUpFront({"render", scene, "-o", missing + ".png", "--size", "64x48"}, missing);
    expectRefusedUpFront(
            {"render",
             scene,
             "-o",
             (mDir / "ok.png").string(),
             "--stats",
             missing + ".json",
             "--size",
             "64x48"},
            missing);
    for (const char* flag : {"--csv", "--json", "--summary"})
        expectRefusedUpFront(
                {"replay", scene, mPath.string(), "--size", "64x48", flag, missing + ".txt"},
                missing);
    expectRefusedUpFront(
            {"replay",
             scene,
             mPath.string(),
             "--size",
             "64x48",
             "--frames-dir",
             (mDir / "tree.ffs" / "frames").string()},
            (mDir / "tree.ffs").string());
    expectRefusedUpFront({"path", "orbit", scene, "-o", missing + ".json"}, missing);
    expectRefusedUpFront({"stats", scene, "--json", missing + ".json"}, missing);
    expectRefusedUpFront(
            {"build",
             "-q",
             "--generate",
             "forest:trees=1",
             "-o",
             (mDir / "b.ffs").string(),
             "--report",
             missing + ".json"},
            missing);
    expectRefusedUpFront(
            {"bench",
             FF_BENCH_DIR "/table2.json",
             "--quick",
             "--out",
             (mDir / "tree.ffs" / "results").string()},
            (mDir / "tree.ffs").string());
    // Before any window opens, so no display is needed to see it.
    expectRefusedUpFront(
            {"view", scene, "--frames", "1", "--screenshot", missing + ".png"}, missing);
    expectRefusedUpFront(
            {"view",
             scene,
             "--frames",
             "1",
             "--screenshot-dir",
             (mDir / "tree.ffs" / "shots").string()},
            (mDir / "tree.ffs").string());
    EXPECT_FALSE(fs::exists(mDir / "ok.png"));
    EXPECT_FALSE(fs::exists(mDir / "b.ffs"));
}

TEST_F(OutputPathTest, AnImageFormatWithoutAWriterIsRefusedBeforeRendering) {
    const std::string bad = (mDir / "image.nosuchformat").string();
    expectRefusedUpFront(
            {"render", mScene.string(), "-o", bad, "--size", "64x48"}, bad, 2); // bad usage
    EXPECT_FALSE(fs::exists(bad));
}

TEST_F(OutputPathTest, AFailedRunLeavesExistingOutputsAsTheyWere) {
    const fs::path image = mDir / "keep.png";
    const std::vector<unsigned char> previous = {'n', 'o', 't', ' ', 'a', ' ', 'p', 'n', 'g'};
    writeBytes(image, previous);
    const std::string missing = (mDir / "no-such-dir" / "stats.json").string();
    expectRefusedUpFront(
            {"render",
             mScene.string(),
             "-o",
             image.string(),
             "--stats",
             missing,
             "--size",
             "64x48"},
            missing);
    EXPECT_EQ(readBytes(image), previous);

    // A run that succeeds replaces the file whole and leaves no temporary beside it.
    const ProcessResult r =
            runFarfield({"render", mScene.string(), "-o", image.string(), "--size", "64x48"}, mDir);
    ASSERT_EQ(r.exitCode, 0) << r.describe();
    EXPECT_EQ(decodeImage(image).width, 64);
    expectNoTemporaries();
}

} // namespace
} // namespace ff::viewer::test
