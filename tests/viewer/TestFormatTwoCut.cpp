// Format 2 stores the same hierarchy as format 1 in fewer bytes; the cut a view draws must not
// change with it. Two things made it: records that stored only their bounds, which the ε rule
// measured instead of the octree cells (a node's bounds reach past its cell by up to a
// triangle), and leaves of thousands of triangles, drawn whole wherever their cell covers more
// than ε pixels, in every placement of an instanced prototype (docs/results, "Format 2 paged").

#include "FarfieldProcess.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

namespace ff::viewer::test {
namespace {

namespace fs = std::filesystem;

struct Cut {
    double triangles = 0;
    double cubes = 0;
};

Cut cutOf(const fs::path& scene, const std::vector<std::string>& view, const fs::path& dir) {
    const fs::path stats = dir / "stats.json";
    std::vector<std::string> args = {
            "render", scene.string(), "-o", (dir / "cut.png").string(), "--size", "320x240",
            "--stats", stats.string()};
    args.insert(args.end(), view.begin(), view.end());
    const ProcessResult rendered = runFarfield(args, dir);
    EXPECT_TRUE(rendered.exited && rendered.exitCode == 0) << rendered.describe();
    const nlohmann::json frame = readJsonFile(stats)["frames"].back();
    return {frame.value("triangles_drawn", 0.0), frame.value("cubes_drawn", 0.0)};
}

TEST(FormatTwoCutTest, AnInstancedTreeIsCutWhereFormatOneCutsIt) {
    const fs::path dir = freshTestDir();
    for (const int format : {1, 2}) {
        const ProcessResult built = runFarfield(
                {"build", "-q", "--generate", "forest:trees=16", "--format", std::to_string(format),
                 "-o", (dir / ("forest" + std::to_string(format) + ".ffs")).string(),
                 "--report", (dir / ("forest" + std::to_string(format) + ".json")).string()},
                dir);
        ASSERT_TRUE(built.exited && built.exitCode == 0) << built.describe();
    }
    // The tree, the forest's one prototype, is placed 16 times: its leaves are the octree's,
    // not 4,096 triangles.
    const nlohmann::json report = readJsonFile(dir / "forest2.json");
    EXPECT_EQ(report.value("smallest_cluster_leaf_triangles", 0), 16);
    EXPECT_EQ(report.value("cluster_leaf_triangles", 0), 16);
    // From the forest's corner, near to far: the cut goes from mostly triangles to mostly
    // cubes. Before, format 2 drew 2.6 to 16 times format 1's triangles here.
    for (const char* eye : {"-40,8,-40", "-80,10,-80", "-160,20,-160"}) {
        SCOPED_TRACE(eye);
        const std::vector<std::string> view = {"--eye", eye, "--target", "0,2,0", "--fov", "60"};
        const Cut one = cutOf(dir / "forest1.ffs", view, dir);
        const Cut two = cutOf(dir / "forest2.ffs", view, dir);
        ASSERT_GT(one.triangles, 0.0);
        ASSERT_GT(one.cubes, 0.0);
        EXPECT_LE(two.triangles, 1.25 * one.triangles);
        EXPECT_NEAR(two.cubes, one.cubes, 0.05 * one.cubes);
    }
}

} // namespace
} // namespace ff::viewer::test
