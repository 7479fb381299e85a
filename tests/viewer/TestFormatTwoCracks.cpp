// Format 2 quantizes positions on one grid per prototype, so a vertex two clusters share decodes
// to the same float in both and neighbouring clusters meet exactly (FORMAT.md §6.3). A crack
// would show as background through a surface: a pixel format 1 covers, format 2 does not, whose
// four neighbours format 2 covers (a silhouette that moved by a fraction of a pixel has
// uncovered neighbours, a hole inside the surface has none). The same holds for stand-ins.

#include "FarfieldProcess.h"

#include <gtest/gtest.h>

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

namespace ff::viewer::test {
namespace {

namespace fs = std::filesystem;

bool covered(const runtime::Image& image, int x, int y) {
    return image
                   .rgba[(static_cast<std::size_t>(y) * static_cast<std::size_t>(image.width) +
                          static_cast<std::size_t>(x)) *
                                 4 +
                         3] > 0;
}

/** Pixels `reference` covers and `image` does not although its four neighbours are covered. */
std::uint64_t crackPixels(const runtime::Image& image, const runtime::Image& reference) {
    std::uint64_t cracks = 0;
    for (int y = 1; y + 1 < image.height; ++y)
        for (int x = 1; x + 1 < image.width; ++x)
            if (covered(reference, x, y) && !covered(image, x, y) && covered(image, x - 1, y) &&
                covered(image, x + 1, y) && covered(image, x, y - 1) && covered(image, x, y + 1))
                ++cracks;
    return cracks;
}

class FormatTwoCrackTest : public ::testing::TestWithParam<std::string> {};

TEST_P(FormatTwoCrackTest, NoBackgroundShowsBetweenClusters) {
    const fs::path dir = freshTestDir();
    for (const int format : {1, 2}) {
        const ProcessResult built = runFarfield(
                {"build",
                 "-q",
                 "--generate",
                 GetParam(),
                 "--format",
                 std::to_string(format),
                 "-o",
                 (dir / ("scene" + std::to_string(format) + ".ffs")).string()},
                dir);
        ASSERT_TRUE(built.exited && built.exitCode == 0) << built.describe();
    }
    const std::vector<std::vector<std::string>> views = {
            {},
            {"--azimuth", "130", "--elevation", "-25", "--distance", "1.6"},
            {"--elevation",
             "85",
             "--distance",
             "0.9"}, // close and from above: most clusters on screen
    };
    std::uint64_t surface = 0;
    for (std::size_t v = 0; v < views.size(); ++v) {
        runtime::Image images[2];
        for (int format = 1; format <= 2; ++format) {
            const fs::path png =
                    dir / ("view" + std::to_string(v) + "_" + std::to_string(format) + ".png");
            std::vector<std::string> args = {
                    "--size", "480x360", "--epsilon", "0", "--coverage-alpha"};
            args.insert(args.end(), views[v].begin(), views[v].end());
            images[format - 1] = renderToImage(
                    dir / ("scene" + std::to_string(format) + ".ffs"), png, args, dir);
            ASSERT_EQ(images[format - 1].width, 480);
        }
        surface += coveredPixels(images[0]);
        EXPECT_EQ(crackPixels(images[1], images[0]), 0u) << "view " << v;
        // The measure finds holes: format 1 against itself with one pixel punched out.
        runtime::Image punched = images[0];
        for (int y = images[0].height / 3; y < images[0].height; ++y) {
            const auto at = (static_cast<std::size_t>(y) * static_cast<std::size_t>(punched.width) +
                             static_cast<std::size_t>(punched.width / 2)) *
                            4;
            if (covered(images[0], punched.width / 2, y) &&
                covered(images[0], punched.width / 2, y - 1) &&
                covered(images[0], punched.width / 2, y + 1)) {
                punched.rgba[at + 3] = 0;
                EXPECT_EQ(crackPixels(punched, images[0]), 1u) << "view " << v;
                break;
            }
        }
    }
    EXPECT_GT(surface, 100000u) << "the views show little of the surface";
}

// Stand-ins (builder/src/StandIns.h) keep their cell's border edges, so neighbours drawn at
// different levels, or one as a stand-in and one as its triangles, still meet exactly. Forced
// over the cubes at a fine and a coarse ε, a frame mixes stand-ins of several levels with
// triangles.
TEST_P(FormatTwoCrackTest, StandInsOfMixedLevelsLeaveNoBackground) {
    const fs::path dir = freshTestDir();
    const fs::path scene = dir / "scene.ffs";
    const ProcessResult built = runFarfield(
            {"build", "-q", "--generate", GetParam(), "--format", "2", "--stand-ins", "-o", scene.string()},
            dir);
    ASSERT_TRUE(built.exited && built.exitCode == 0) << built.describe();
    const std::vector<std::vector<std::string>> views = {
            {},
            {"--azimuth", "130", "--elevation", "-25", "--distance", "1.6"},
            {"--elevation", "85", "--distance", "0.9"},
            {"--elevation", "30", "--distance", "0.5"}, // inside the sphere: the far side far
    };
    int mixed = 0; // frames of several stand-ins (a smooth sphere far off is one stand-in)
    for (std::size_t v = 0; v < views.size(); ++v) {
        std::vector<std::string> common = {"--size", "480x360", "--coverage-alpha"};
        common.insert(common.end(), views[v].begin(), views[v].end());
        std::vector<std::string> full = common;
        full.insert(full.end(), {"--method", "full"});
        const runtime::Image reference =
                renderToImage(scene, dir / ("full" + std::to_string(v) + ".png"), full, dir);
        std::vector<std::string> exact = common;
        exact.insert(exact.end(), {"--epsilon", "0", "--representation", "simplified"});
        EXPECT_EQ(
                differingPixels(
                        renderToImage(scene, dir / ("exact" + std::to_string(v) + ".png"), exact, dir),
                        reference),
                0u)
                << "view " << v << ": ε = 0 draws a stand-in";
        for (const char* epsilon : {"2", "32"}) {
            const fs::path stats = dir / "stats.json";
            std::vector<std::string> args = common;
            args.insert(
                    args.end(),
                    {"--epsilon", epsilon, "--representation", "simplified", "--stats", stats.string()});
            const runtime::Image image = renderToImage(
                    scene, dir / ("view" + std::to_string(v) + "_" + epsilon + ".png"), args, dir);
            const nlohmann::json frame = readJsonFile(stats)["frames"].back();
            const auto standIns = frame["stand_ins_drawn"].get<std::uint64_t>();
            EXPECT_GT(standIns, 0u) << "view " << v << " ε " << epsilon;
            mixed += standIns > 1 ? 1 : 0;
            EXPECT_EQ(crackPixels(image, reference), 0u) << "view " << v << " ε " << epsilon;
        }
    }
    EXPECT_GT(mixed, 0);
}

INSTANTIATE_TEST_SUITE_P(
        Surfaces,
        FormatTwoCrackTest,
        ::testing::Values("terrain:triangles=200000", "sphere:triangles=200000"),
        [](const ::testing::TestParamInfo<std::string>& p) {
            return p.param.substr(0, p.param.find(':'));
        });

} // namespace
} // namespace ff::viewer::test
