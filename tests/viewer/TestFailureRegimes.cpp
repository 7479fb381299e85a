// Failure regimes with bounds, so a regression fails CI. Chamberlain et al. '96 §5.1: color
// cubes "tear" on contiguous surfaces that are large relative to the leaf cells when seen off
// the sampled axes — nearly transparent faces let the background through.

#include "FarfieldProcess.h"

#include <ff/runtime/ImageMetrics.h>

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <set>
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

/** `a` followed by `b`: a view's flags plus a method's. */
std::vector<std::string> concat(std::vector<std::string> a, const std::vector<std::string>& b) {
    a.insert(a.end(), b.begin(), b.end());
    return a;
}

/** Renders `scene` with `flags` into dir/name and decodes it; a failed render fails the test. */
runtime::Image render(const fs::path& dir, const fs::path& scene, const std::string& name, const std::vector<std::string>& flags) {
    const ProcessResult r = runFarfield(concat({"render", scene.string(), "-o", (dir / name).string()}, flags), dir);
    EXPECT_EQ(r.exitCode, 0) << r.describe();
    return decodeImage(dir / name);
}

/** Renders and returns the frame statistics `render` prints as one JSON line on stdout (a
 *  null json if it printed none). */
nlohmann::json renderStats(const fs::path& dir, const fs::path& scene, const std::vector<std::string>& flags) {
    const ProcessResult r = runFarfield(concat({"render", scene.string(), "-o", (dir / "stats.png").string()}, flags), dir);
    EXPECT_EQ(r.exitCode, 0) << r.describe();
    const std::size_t last = r.out.rfind('{');
    return last == std::string::npos ? nlohmann::json() : nlohmann::json::parse(r.out.substr(last), nullptr, false);
}

fs::path buildScene(const fs::path& dir, const std::string& name, const std::vector<std::string>& flags) {
    const fs::path scene = dir / name;
    const ProcessResult r = runFarfield(concat({"build", "-q", "-o", scene.string()}, flags), dir);
    EXPECT_EQ(r.exitCode, 0) << r.describe();
    return scene;
}

double fraction(std::uint64_t part, std::uint64_t whole) {
    return static_cast<double>(part) / static_cast<double>(std::max<std::uint64_t>(whole, 1));
}

// The scanned skull (100k triangles, one contiguous surface) 45 degrees off every sampled axis,
// from where most of it is drawn as sub-pixel cubes. Measured when this test was written
// (Debug and Release agree): holes 0.5-0.6 % of the covered pixels, over-coverage 2.6 % at 6
// radii and 12.5 % at 12, in both cube drawing modes. The bounds leave room for noise, not for
// a regression.
TEST(FailureRegimeTest, TearingOfAScannedSurfaceSeen45DegreesOffAxisIsBounded) {
    const fs::path dir = freshTestDir();
    const fs::path scene = buildScene(dir, "skull.ffs", {FF_SHARED_DATA_DIR "/scanned/skull/skull.glb"});
    for (const char* distance : {"6", "12"}) {
        const std::vector<std::string> view = {"--size", "160x120", "--distance", distance, "--azimuth", "45",
                                               "--elevation", "35", "--coverage-alpha"};
        const runtime::Image reference = render(dir, scene, "reference.png", concat(view, {"--method", "full", "--supersample", "4"}));
        ASSERT_EQ(reference.width, 160);
        for (const char* mode : {"faces", "points"}) {
            SCOPED_TRACE(std::string("distance ") + distance + ", cubes as " + mode);
            const runtime::Image approximation = render(dir, scene, std::string(mode) + ".png", concat(view, {"--cube-draw", mode}));
            ASSERT_EQ(approximation.width, 160);
            const Coverage c = compare(approximation, reference);
            ASSERT_GT(c.covered, 100u);
            EXPECT_LE(static_cast<double>(c.holes), 0.02 * static_cast<double>(c.covered));
            EXPECT_LE(static_cast<double>(c.overCovered), 0.20 * static_cast<double>(c.covered));
        }
    }
}

// The second tearing case: a large smooth closed surface (a 50k-triangle sphere) 45 degrees
// off the sampled axes. Measured when written: holes 0.13 % at 2 radii (8 of 6004 pixels), none
// at 6; over-coverage 0 at ε = 1. Bounds: 1 % holes, 5 % over-coverage.
TEST(FailureRegimeTest, TearingOfALargeSmoothSphereSeen45DegreesOffAxisIsBounded) {
    const fs::path dir = freshTestDir();
    const fs::path scene = buildScene(dir, "sphere.ffs", {"--generate", "sphere:triangles=50000"});
    for (const char* distance : {"2", "6"}) {
        const std::vector<std::string> view = {"--size", "160x120", "--distance", distance, "--azimuth", "45",
                                               "--elevation", "35", "--coverage-alpha"};
        const runtime::Image reference = render(dir, scene, "reference.png", concat(view, {"--method", "full", "--supersample", "4"}));
        for (const char* mode : {"faces", "points"}) {
            SCOPED_TRACE(std::string("distance ") + distance + ", cubes as " + mode);
            const Coverage c = compare(render(dir, scene, "a.png", concat(view, {"--cube-draw", mode})), reference);
            ASSERT_GT(c.covered, 300u);
            EXPECT_LE(fraction(c.holes, c.covered), 0.01);
            EXPECT_LE(fraction(c.overCovered, c.covered), 0.05);
        }
    }
}

// Venetian blinds (Chamberlain et al. §3.2): 100 slabs 0.02 apart, split into cells, far enough
// that the cells are sub-pixel. Seen 3 degrees above the slabs, the reference is opaque (each
// ray crosses several slabs) but each cube's faces say "25 % covered" from the side and "fully
// covered" from above: the interpolated cube leaks. Measured when written at 12 radii: 37 % of
// the covered pixels are holes at the grazing view, 3 % at 45 degrees. Refusing anisotropic
// cubes (--cube-anisotropy 0.6) brings the grazing view to 3.6 % by drawing the slabs' triangles.
TEST(FailureRegimeTest, VenetianBlindsLeakAtGrazingViewsUnlessAnisotropicCubesAreRefused) {
    const fs::path dir = freshTestDir();
    const fs::path scene = buildScene(
            dir, "blinds.ffs",
            {"--generate", "blinds:slabs=100,spacing=0.02,thickness=0.005,width=2,depth=0.5,tessellation=16"});
    struct View {
        const char* elevation;
        double defaultHoles;   ///< bound with every cube accepted
        double refusedHoles;   ///< bound with --cube-anisotropy 0.6
    };
    for (const View& v : {View{"3", 0.50, 0.10}, View{"45", 0.08, 0.08}}) {
        SCOPED_TRACE(std::string("elevation ") + v.elevation);
        const std::vector<std::string> view = {"--size", "160x120", "--distance", "12", "--azimuth", "20",
                                               "--elevation", v.elevation, "--coverage-alpha"};
        const runtime::Image reference = render(dir, scene, "reference.png", concat(view, {"--method", "full", "--supersample", "4"}));
        const Coverage accepted = compare(render(dir, scene, "accepted.png", view), reference);
        const Coverage refused = compare(render(dir, scene, "refused.png", concat(view, {"--cube-anisotropy", "0.6"})), reference);
        ASSERT_GT(accepted.covered, 150u);
        EXPECT_LE(fraction(accepted.holes, accepted.covered), v.defaultHoles);
        EXPECT_LE(fraction(refused.holes, refused.covered), v.refusedHoles);
        EXPECT_LE(refused.holes, accepted.holes);
    }
}

// The viewer inside the scene, near field everywhere. The hierarchical path must not cost more
// than brute force by more than 10 %: timed in `farfield bench` (bench/inside.json), bounded
// here by the work each draws — triangles plus cubeCost (6) per cube, the builder's own cost
// model. Frustum culling makes the hierarchy draw less than `--method full` inside the tree.
TEST(FailureRegimeTest, InsideTheSceneTheHierarchyDrawsNoMoreThanBruteForce) {
    const fs::path dir = freshTestDir();
    const fs::path tree = buildScene(dir, "tree.ffs", {"--generate", "forest:trees=1"});
    const fs::path forest = buildScene(dir, "forest.ffs", {"--generate", "forest:trees=16"});
    for (const auto& [scene, distance] : {std::pair{tree, "0.3"}, std::pair{tree, "0.8"}, std::pair{forest, "0.2"}}) {
        SCOPED_TRACE(scene.filename().string() + " at " + distance + " radii");
        const std::vector<std::string> view = {"--size", "160x120", "--distance", distance, "--azimuth", "30", "--elevation", "5"};
        const nlohmann::json full = renderStats(dir, scene, concat(view, {"--method", "full"}));
        const nlohmann::json hierarchical = renderStats(dir, scene, view);
        ASSERT_TRUE(full.is_object() && hierarchical.is_object());
        const double fullWork = full["triangles_drawn"].get<double>();
        const double work = hierarchical["triangles_drawn"].get<double>() + 6.0 * hierarchical["cubes_drawn"].get<double>();
        ASSERT_GT(fullWork, 0.0);
        EXPECT_LE(work, 1.10 * fullWork);
    }
}

// Coordinates offset by 10^6 and scaled by 10^-3: the tree becomes 1 cm tall at a million units
// from the origin, where a float's spacing is 0.06 units. Without the file frame (a
// double-precision origin in the header) the whole tree collapsed to one float position and
// nothing was drawn (measured: 0 of 4062 pixels). Now every view, including one taken from a
// camera path written in world coordinates, matches the untransformed tree.
TEST(FailureRegimeTest, ASceneFarFromTheOriginAndTinyRendersLikeTheOriginal) {
    const fs::path dir = freshTestDir();
    const fs::path plain = buildScene(dir, "plain.ffs", {"--generate", "forest:trees=1"});
    const fs::path far = buildScene(dir, "far.ffs", {"--generate", "forest:trees=1", "--offset", "1e6,1e6,1e6", "--scale", "1e-3", "--report", (dir / "far.json").string()});
    const nlohmann::json report = readJsonFile(dir / "far.json");
    ASSERT_TRUE(report.contains("origin"));
    EXPECT_NEAR(report["origin"][0].get<double>(), 1e6, 1.0);

    auto expectSame = [&](const std::vector<std::string>& plainView, const std::vector<std::string>& farView) {
        const std::vector<std::string> common = {"--size", "160x120", "--coverage-alpha"};
        const runtime::Image a = render(dir, plain, "plain.png", concat(plainView, common));
        const runtime::Image b = render(dir, far, "far.png", concat(farView, common));
        const Coverage c = compare(b, a);
        ASSERT_GT(c.covered, 500u);
        EXPECT_LE(fraction(c.holes + c.overCovered, c.covered), 0.002) << "cracks or shifted silhouette";
        const Result<runtime::ColorError> error = runtime::colorError(b, a);
        ASSERT_TRUE(error.isOk());
        EXPECT_GE(error->psnrSrgb, 40.0);
    };
    for (const char* azimuth : {"30", "135"}) {
        SCOPED_TRACE(std::string("orbit view, azimuth ") + azimuth);
        const std::vector<std::string> view = {"--distance", "2", "--azimuth", azimuth, "--elevation", "20"};
        expectSame(view, view);
    }
    // A slow camera path in world coordinates: a jittering camera would move the image by whole
    // float steps (0.06 units, 6 tree heights) between frames.
    const fs::path plainPath = dir / "plain-path.json";
    const fs::path farPath = dir / "far-path.json";
    for (const auto& [scene, path] : {std::pair{plain, plainPath}, std::pair{far, farPath}})
        ASSERT_EQ(runFarfield({"path", "orbit", scene.string(), "-o", path.string(), "--frames", "720"}, dir).exitCode, 0);
    for (const char* frame : {"0", "1", "2"}) {
        SCOPED_TRACE(std::string("path frame ") + frame);
        expectSame({"--path", plainPath.string(), "--path-frame", frame}, {"--path", farPath.string(), "--path-frame", frame});
    }
}

// Popping and flicker along a slow fly-through: temporal instability (docs/metrics.md) of the
// hierarchy against all geometry, 12 frames moving 0.2 % of the scene radius each, synchronous.
// Measured when written: mean 0.00031, worst frame pair 0.00038 (linear luminance, 0..1).
/** The frames of `replay --sync` of `scene` along `path` at `epsilon` (160 x 120). */
std::vector<runtime::Image> replayFrames(
        const fs::path& dir,
        const fs::path& scene,
        const fs::path& path,
        const std::string& epsilon,
        const std::string& name,
        const std::vector<std::string>& flags = {}) {
    const fs::path frames = dir / name;
    fs::create_directories(frames);
    const ProcessResult r = runFarfield(
            concat({"replay", scene.string(), path.string(), "--sync", "--size", "160x120", "--epsilon", epsilon,
                    "--frames-dir", frames.string()},
                   flags),
            dir);
    EXPECT_EQ(r.exitCode, 0) << r.describe();
    std::vector<runtime::Image> images;
    for (int f = 0;; ++f) {
        char file[32];
        std::snprintf(file, sizeof(file), "frame-%05d.png", f);
        if (!fs::exists(frames / file))
            break;
        images.push_back(decodeImage(frames / file));
    }
    return images;
}

TEST(FailureRegimeTest, PoppingAlongASlowFlyThroughIsBounded) {
    const fs::path dir = freshTestDir();
    const fs::path scene = buildScene(dir, "forest.ffs", {"--generate", "forest:trees=16"});
    // Sixteen trees in a square about 50 units across: fly in from its corner, slowly.
    const fs::path path = dir / "slow.json";
    {
        std::ofstream out(path);
        out << R"({"interpolation": "linear", "frames": 12, "keyframes": [
            {"time": 0.0, "position": [-40, 12, -40], "target": [0, 3, 0], "fov": 45},
            {"time": 1.0, "position": [-39.4, 12, -39.8], "target": [0, 3, 0], "fov": 45}]})";
    }
    const std::vector<runtime::Image> approximation = replayFrames(dir, scene, path, "1", "approximation");
    const std::vector<runtime::Image> reference = replayFrames(dir, scene, path, "0", "reference");
    ASSERT_EQ(approximation.size(), 12u);
    ASSERT_EQ(reference.size(), 12u);
    const Result<runtime::TemporalInstability> instability = runtime::temporalInstability(approximation, reference);
    ASSERT_TRUE(instability.isOk()) << instability.status().toString();
    std::printf("temporal instability: mean %.5f, worst frame pair %.5f\n", instability->mean, instability->maxFrame);
    EXPECT_LE(instability->mean, 0.0015);
    EXPECT_LE(instability->maxFrame, 0.003);
}

/** A terrain (`generate`) built with `buildFlags`, flown over slowly (`from` to `to`, looking at its middle)
 *  so that cells switch between a stand-in (`column`: the telemetry column counting them) and
 *  the triangles below it, or between stand-ins of two levels, as they come nearer: the same
 *  bound as the cubes' popping above. */
void expectStandInsSwitchWithinThePoppingBound(
        const std::string& generate,
        const std::vector<std::string>& buildFlags,
        const std::string& column,
        const std::string& from,
        const std::string& to) {
    const fs::path dir = freshTestDir();
    std::vector<std::string> build = {"--generate", generate, "--format", "2"};
    build.insert(build.end(), buildFlags.begin(), buildFlags.end());
    const fs::path scene = buildScene(dir, "terrain.ffs", build);
    const fs::path path = dir / "low.json";
    {
        std::ofstream out(path);
        out << R"({"interpolation": "linear", "frames": 12, "keyframes": [
            {"time": 0.0, "position": )" << from << R"(, "target": [40, 0, 40], "fov": 45},
            {"time": 1.0, "position": )" << to << R"(, "target": [40, 0, 40], "fov": 45}]})";
    }
    const fs::path csv = dir / "frames.csv";
    const std::vector<runtime::Image> approximation =
            replayFrames(dir, scene, path, "1", "approximation", {"--csv", csv.string()});
    const std::vector<runtime::Image> reference = replayFrames(dir, scene, path, "0", "reference");
    ASSERT_EQ(approximation.size(), 12u);
    ASSERT_EQ(reference.size(), 12u);
    // Stand-ins were drawn, and how many changed along the flight.
    std::ifstream rows(csv);
    std::string header;
    std::getline(rows, header);
    std::size_t index = 0;
    for (std::size_t at = 0, next = 0; (next = header.find(',', at)) != std::string::npos || at < header.size();
         at = next + 1, ++index) {
        if (header.substr(at, next == std::string::npos ? std::string::npos : next - at) == column)
            break;
        if (next == std::string::npos)
            FAIL() << "no " << column << " column in " << header;
    }
    std::set<long> counts;
    for (std::string row; std::getline(rows, row);) {
        std::size_t at = 0;
        for (std::size_t c = 0; c < index; ++c)
            at = row.find(',', at) + 1;
        counts.insert(std::stol(row.substr(at)));
    }
    EXPECT_GT(*counts.rbegin(), 0) << "no stand-in drawn";
    EXPECT_GT(counts.size(), 1u) << "the cut never changed: nothing switched";
    const Result<runtime::TemporalInstability> instability = runtime::temporalInstability(approximation, reference);
    ASSERT_TRUE(instability.isOk()) << instability.status().toString();
    std::printf("temporal instability: mean %.5f, worst frame pair %.5f\n", instability->mean, instability->maxFrame);
    EXPECT_LE(instability->mean, 0.0015);
    EXPECT_LE(instability->maxFrame, 0.003);
}

TEST(FailureRegimeTest, StandInsSwitchingAlongASlowFlightStayWithinThePoppingBound) {
    // Low over the terrain.
    expectStandInsSwitchWithinThePoppingBound(
            "terrain:triangles=200000", {"--stand-ins"}, "stand_ins", "[-120, 25, -120]", "[-100, 24, -102]");
}

TEST(FailureRegimeTest, SplatsSwitchingAlongASlowFlightStayWithinThePoppingBound) {
    // From afar, where cells small on screen are splats (8 splat sets at the start, 5 at the end;
    // a small terrain: splatting is the build's slow part under the sanitizers).
    expectStandInsSwitchWithinThePoppingBound(
            "terrain:triangles=50000", {"--splats", "8"}, "splat_sets", "[-600, 300, -600]", "[-520, 260, -520]");
}

} // namespace
} // namespace ff::viewer::test
