// Splats drawn (builder/src/Splats.h, docs/methods.md §13): opaque, depth-tested points whose
// diameter covers twice their error, so a closed surface shows no background through them at
// any splat size or shape; `--representation` forces each kind a file holds (a cell without it
// falls back to the nearest kept kind); ε = 0 draws none.

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
    if (x < 0 || y < 0 || x >= image.width || y >= image.height)
        return false;
    return image.rgba[(static_cast<std::size_t>(y) * static_cast<std::size_t>(image.width) +
                       static_cast<std::size_t>(x)) *
                              4 +
                      3] > 0;
}

/** Pixels `image` leaves uncovered that `reference` covers two pixels deep inside its
 *  silhouette (where splats may not round the outline off): holes, however large. */
std::uint64_t holePixels(const runtime::Image& image, const runtime::Image& reference) {
    std::uint64_t holes = 0;
    for (int y = 0; y < reference.height; ++y)
        for (int x = 0; x < reference.width; ++x) {
            bool inner = true;
            for (int dy = -2; dy <= 2 && inner; ++dy)
                for (int dx = -2; dx <= 2 && inner; ++dx)
                    inner = covered(reference, x + dx, y + dy);
            holes += inner && !covered(image, x, y) ? 1u : 0u;
        }
    return holes;
}

struct Drawn {
    std::uint64_t standIns = 0;
    std::uint64_t splatSets = 0;
    std::uint64_t splats = 0;
    std::uint64_t fallbacks = 0; ///< cells drawn as the nearest kept kind to the forced one
    std::uint64_t cubes = 0;
};

Drawn drawnIn(const fs::path& stats) {
    const nlohmann::json frame = readJsonFile(stats)["frames"].back();
    return {frame["stand_ins_drawn"].get<std::uint64_t>(),
            frame["splat_sets_drawn"].get<std::uint64_t>(),
            frame["splats_drawn"].get<std::uint64_t>(),
            frame["representation_fallbacks"].get<std::uint64_t>(),
            frame["cubes_drawn"].get<std::uint64_t>()};
}

fs::path buildSphere(const fs::path& dir, const std::vector<std::string>& flags) {
    const fs::path scene = dir / "sphere.ffs";
    std::vector<std::string> args = {
            "build", "-q", "--generate", "sphere:triangles=200000", "--format", "2", "-o", scene.string()};
    args.insert(args.end(), flags.begin(), flags.end());
    const ProcessResult built = runFarfield(args, dir);
    EXPECT_TRUE(built.exited && built.exitCode == 0) << built.describe();
    return scene;
}

TEST(SplatRenderingTest, SplatsLeaveNoHolesOnAClosedSurface) {
    const fs::path dir = freshTestDir();
    const fs::path scene = buildSphere(dir, {"--splats", "8"});
    std::uint64_t splatsDrawn = 0;
    for (const char* distance : {"6", "12"}) {
        const std::vector<std::string> common = {
                "--size", "480x360", "--coverage-alpha", "--distance", distance, "--elevation", "20"};
        std::vector<std::string> full = common;
        full.insert(full.end(), {"--method", "full"});
        const runtime::Image reference =
                renderToImage(scene, dir / (std::string("full") + distance + ".png"), full, dir);
        for (const auto& [size, shape] : std::vector<std::pair<std::string, std::string>>{
                     {"1", "square"}, {"2", "round"}, {"2", "square"}, {"3", "round"}}) {
            for (const char* epsilon : {"1"}) { // larger ε draws the same: the size limit binds
                const fs::path stats = dir / "stats.json";
                std::vector<std::string> args = common;
                args.insert(
                        args.end(),
                        {"--representation", "splats", "--epsilon", epsilon, "--splat-size", size,
                         "--splat-shape", shape, "--stats", stats.string()});
                const std::string label = std::string(distance) + "_" + size + shape + "_" + epsilon;
                const runtime::Image image = renderToImage(scene, dir / (label + ".png"), args, dir);
                splatsDrawn += drawnIn(stats).splats;
                EXPECT_EQ(holePixels(image, reference), 0u) << label;
            }
        }
        // The measure finds holes: the reference with a 3 x 3 block cleared in its middle.
        runtime::Image punched = reference;
        for (int y = reference.height / 2 - 1; y <= reference.height / 2 + 1; ++y)
            for (int x = reference.width / 2 - 1; x <= reference.width / 2 + 1; ++x)
                punched.rgba[(static_cast<std::size_t>(y) * static_cast<std::size_t>(punched.width) +
                              static_cast<std::size_t>(x)) *
                                     4 +
                             3] = 0;
        EXPECT_EQ(holePixels(punched, reference), 9u);
    }
    EXPECT_GT(splatsDrawn, 2000u) << "the views drew few splats";

    // The file keeps no simplified copy: forcing one, cells below ε fall back to their splats
    // where those leave no holes, else to their cube, counted.
    const fs::path stats = dir / "forced_simplified.json";
    (void)renderToImage(
            scene,
            dir / "forced_simplified.png",
            {"--size", "480x360", "--distance", "24", "--elevation", "20", "--epsilon", "4",
             "--representation", "simplified", "--stats", stats.string()},
            dir);
    const Drawn forced = drawnIn(stats);
    EXPECT_EQ(forced.standIns, 0u);
    EXPECT_GT(forced.splatSets, 0u) << "no cell fell back to its splats";
    EXPECT_GT(forced.fallbacks, forced.splatSets) << "no cell fell back to its cube";
}

TEST(SplatRenderingTest, EachRepresentationCanBeForcedAndEpsilonZeroDrawsNone) {
    const fs::path dir = freshTestDir();
    // A sphere's cells keep simplified stand-ins, but in pages of 4 KiB the upper cells' are too
    // large: by rule those keep splats, drawn from afar (measured, they do not pay).
    const fs::path scene = buildSphere(
            dir, {"--stand-ins", "--splats", "8", "--stand-in-choice", "rule", "--page-size", "4096"});
    const std::vector<std::string> common = {"--size", "320x240", "--coverage-alpha", "--distance", "48"};
    const auto drawnWith = [&](const std::vector<std::string>& extra,
                               const std::string& label,
                               const std::string& distance = "48") {
        const fs::path stats = dir / (label + ".json");
        std::vector<std::string> args = common;
        args[4] = distance;
        args.insert(args.end(), extra.begin(), extra.end());
        args.insert(args.end(), {"--stats", stats.string()});
        renderToImage(scene, dir / (label + ".png"), args, dir);
        return drawnIn(stats);
    };
    const Drawn cube = drawnWith({"--representation", "cube", "--epsilon", "4"}, "cube");
    EXPECT_EQ(cube.standIns + cube.splatSets + cube.fallbacks, 0u);
    // A forced kind a cell did not keep falls back to the nearest kept one (the other stand-in,
    // else the cube), counted: every cell drawn as the other kind is among the fallbacks.
    const Drawn simplified = drawnWith({"--representation", "simplified", "--epsilon", "4"}, "simplified");
    EXPECT_GT(simplified.standIns, 0u);
    EXPECT_LE(simplified.splatSets, simplified.fallbacks);
    const Drawn splats = drawnWith({"--representation", "splats", "--epsilon", "4"}, "splats");
    EXPECT_GT(splats.splatSets, 0u);
    EXPECT_GT(splats.splats, 0u);
    EXPECT_LE(splats.standIns, splats.fallbacks);
    const Drawn automatic = drawnWith({"--epsilon", "4"}, "auto");
    EXPECT_GT(automatic.standIns + automatic.splatSets, 0u);
    EXPECT_EQ(automatic.fallbacks, 0u);

    // Nearer, with cells below ε that keep a simplified copy but no splats (the root alone
    // keeps splats) and leaves that keep neither: forced splats fall back to each, counted.
    const Drawn nearer = drawnWith(
            {"--representation", "splats", "--epsilon", "16"}, "splats_nearer", "12");
    EXPECT_GT(nearer.standIns, 0u) << "no cell fell back to its simplified copy";
    EXPECT_GT(nearer.fallbacks, nearer.standIns) << "no cell fell back to its cube";
    // The front-to-back walk falls back alike (cells it finds hidden it never expands).
    const Drawn occluding = drawnWith(
            {"--representation", "splats", "--epsilon", "16", "--occlusion", "on"}, "splats_nearer_occlusion", "12");
    EXPECT_GT(occluding.standIns, 0u);
    EXPECT_GT(occluding.fallbacks, occluding.standIns);
    EXPECT_LE(occluding.fallbacks, nearer.fallbacks);

    // ε = 0 draws every triangle, whatever is forced.
    std::vector<std::string> full = common;
    full.insert(full.end(), {"--method", "full"});
    const runtime::Image reference = renderToImage(scene, dir / "full.png", full, dir);
    for (const char* kind : {"splats", "simplified"}) {
        std::vector<std::string> exact = common;
        exact.insert(exact.end(), {"--epsilon", "0", "--representation", kind});
        EXPECT_EQ(differingPixels(renderToImage(scene, dir / (std::string(kind) + "0.png"), exact, dir), reference), 0u)
                << kind;
    }
}

} // namespace
} // namespace ff::viewer::test
