// Failure regimes with bounds, so a regression fails CI. Chamberlain et al. '96 §5.1: color
// cubes "tear" on contiguous surfaces that are large relative to the leaf cells when seen off
// the sampled axes — nearly transparent faces let the background through.

#include "FarfieldProcess.h"

#include <gtest/gtest.h>

#include <string>

namespace ff::viewer::test {
namespace {

namespace fs = std::filesystem;

struct Coverage {
    std::uint64_t covered = 0;      ///< reference pixels with coverage >= 1/2
    std::uint64_t holes = 0;        ///< of those, background in the approximation (tearing)
    std::uint64_t overCovered = 0;  ///< approximation covered where the reference is not
};

Coverage compare(const runtime::Image& approximation, const runtime::Image& reference) {
    Coverage c;
    for (int y = 0; y < reference.height; ++y) {
        for (int x = 0; x < reference.width; ++x) {
            const bool inReference = reference.pixel(x, y)[3] >= 128;
            const bool inApproximation = approximation.pixel(x, y)[3] >= 128;
            c.covered += inReference ? 1 : 0;
            c.holes += inReference && !inApproximation ? 1 : 0;
            c.overCovered += !inReference && inApproximation ? 1 : 0;
        }
    }
    return c;
}

// The scanned skull (100k triangles, one contiguous surface) 45 degrees off every sampled axis,
// from where most of it is drawn as sub-pixel cubes. Measured when this test was written
// (Debug and Release agree): holes 0.5-0.6 % of the covered pixels, over-coverage 2.6 % at 6
// radii and 12.5 % at 12, in both cube drawing modes. The bounds leave room for noise, not for
// a regression.
TEST(FailureRegimeTest, TearingOfAScannedSurfaceSeen45DegreesOffAxisIsBounded) {
    const fs::path dir = freshTestDir();
    const fs::path scene = dir / "skull.ffs";
    const ProcessResult built = runFarfield(
            {"build", "-q", FF_SHARED_DATA_DIR "/scanned/skull/skull.glb", "-o", scene.string()}, dir);
    ASSERT_EQ(built.exitCode, 0) << built.describe();
    for (const char* distance : {"6", "12"}) {
        const std::vector<std::string> view = {"--size", "160x120", "--distance", distance, "--azimuth", "45",
                                               "--elevation", "35", "--coverage-alpha"};
        auto render = [&](const std::string& name, std::vector<std::string> flags) {
            std::vector<std::string> args = {"render", scene.string(), "-o", (dir / name).string()};
            args.insert(args.end(), view.begin(), view.end());
            args.insert(args.end(), flags.begin(), flags.end());
            const ProcessResult r = runFarfield(args, dir);
            EXPECT_EQ(r.exitCode, 0) << r.describe();
            return decodeImage(dir / name);
        };
        const runtime::Image reference = render("reference.png", {"--method", "full", "--supersample", "4"});
        ASSERT_EQ(reference.width, 160);
        for (const char* mode : {"faces", "points"}) {
            SCOPED_TRACE(std::string("distance ") + distance + ", cubes as " + mode);
            const runtime::Image approximation = render(std::string(mode) + ".png", {"--cube-draw", mode});
            ASSERT_EQ(approximation.width, 160);
            const Coverage c = compare(approximation, reference);
            ASSERT_GT(c.covered, 100u);
            EXPECT_LE(static_cast<double>(c.holes), 0.02 * static_cast<double>(c.covered));
            EXPECT_LE(static_cast<double>(c.overCovered), 0.20 * static_cast<double>(c.covered));
        }
    }
}

} // namespace
} // namespace ff::viewer::test
