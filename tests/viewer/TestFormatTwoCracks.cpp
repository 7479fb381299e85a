// Format 2 quantizes positions on one grid per prototype, so a vertex two clusters share decodes
// to the same float in both and neighbouring clusters meet exactly (FORMAT.md §6.3). A crack
// would show as background through a surface: a pixel format 1 covers, format 2 does not, whose
// four neighbours format 2 covers (a silhouette that moved by a fraction of a pixel has
// uncovered neighbours, a hole inside the surface has none).

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

INSTANTIATE_TEST_SUITE_P(
        Surfaces,
        FormatTwoCrackTest,
        ::testing::Values("terrain:triangles=200000", "sphere:triangles=200000"),
        [](const ::testing::TestParamInfo<std::string>& p) {
            return p.param.substr(0, p.param.find(':'));
        });

} // namespace
} // namespace ff::viewer::test
