// `farfield build` end to end: instancing at scale, bounded memory, deterministic output, and
// clean refusals of bad input (never a signal, never a half-written file).

#include "FarfieldProcess.h"

#include <ff/builder/HierarchyParams.h>
#include <ff/runtime/ImageMetrics.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <set>
#include <string>
#include <vector>

namespace ff::viewer::test {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

const fs::path kData = FF_SHARED_DATA_DIR;
constexpr std::uint64_t kMiB = 1024 * 1024;

/** `farfield build -q <args...> -o <output> --report <report>`; returns the process result. */
ProcessResult build(const fs::path& dir, std::vector<std::string> args, const fs::path& output) {
    args.insert(args.begin(), {"build", "-q"});
    args.insert(
            args.end(),
            {"-o",
             output.string(),
             "--report",
             (dir / (output.stem().string() + ".json")).string()});
    return runFarfield(args, dir);
}

bool exitedWith(const ProcessResult& r, int code) {
    return r.exited && r.exitCode == code;
}

/** No leftover temporary files (.tmp-<pid> of the writer, .farfield-build-* spill folders). */
std::vector<std::string> leftovers(const fs::path& dir) {
    std::vector<std::string> out;
    for (const auto& entry : fs::directory_iterator(dir)) {
        const std::string name = entry.path().filename().string();
        if (name.find(".tmp") != std::string::npos ||
            name.find(".farfield-build") != std::string::npos)
            out.push_back(name);
    }
    return out;
}

// ------------------------------------------------------------------------------------------
// The Chamberlain forest: 16,384 trees cost one tree plus 16,384 transforms.

TEST(BuildCommandTest, ForestOf16384TreesIsOneTreePlusInstances) {
    const fs::path dir = freshTestDir();
    const ProcessResult one = build(dir, {"--generate", "forest:trees=1"}, dir / "tree.ffs");
    ASSERT_TRUE(exitedWith(one, 0)) << one.describe();
    const json tree = readJsonFile(dir / "tree.json");
    const auto treeTriangles = tree.at("stored_triangles").get<std::uint64_t>();
    EXPECT_GT(treeTriangles, 10000u);

    const fs::path forest = dir / "forest.ffs";
    const ProcessResult built = build(dir, {"--generate", "forest:trees=16384"}, forest);
    ASSERT_TRUE(exitedWith(built, 0)) << built.describe();
    RecordProperty("build_seconds", std::to_string(built.seconds));
    std::printf(
            "forest:trees=16384 built in %.1f s (peak RSS %llu MiB)\n",
            built.seconds,
            static_cast<unsigned long long>(built.maxRssBytes / kMiB));
    const json report = readJsonFile(dir / "forest.json");
    ASSERT_TRUE(report.is_object());
    EXPECT_EQ(report.at("prototypes").get<std::uint64_t>(), 1u);
    EXPECT_EQ(report.at("instances").get<std::uint64_t>(), 16384u);
    EXPECT_EQ(report.at("stored_triangles").get<std::uint64_t>(), treeTriangles);
    EXPECT_EQ(report.at("instanced_triangles").get<std::uint64_t>(), 16384u * treeTriangles);
    EXPECT_EQ(report.at("declared_triangles").get<std::uint64_t>(), 16384u * treeTriangles);
    EXPECT_LT(report.at("bytes").at("file").get<std::uint64_t>(), 100 * kMiB);
    EXPECT_EQ(report.at("bytes").at("file").get<std::uint64_t>(), fs::file_size(forest));

    const ProcessResult checked = runFarfield({"check", forest.string()}, dir);
    EXPECT_TRUE(exitedWith(checked, 0)) << checked.describe();

    const fs::path png = dir / "forest.png";
    const ProcessResult rendered = runFarfield(
            {"render",
             forest.string(),
             "-o",
             png.string(),
             "--size",
             "160x120",
             "--distance",
             "2", // near enough that the trees in front are entered (3,607 at ε = 1)
             "--coverage-alpha"},
            dir);
    ASSERT_TRUE(exitedWith(rendered, 0)) << rendered.describe();
    const json stats = json::parse(rendered.out, nullptr, false);
    ASSERT_TRUE(stats.is_object()) << "stdout is not one JSON object per frame: " << rendered.out;
    EXPECT_GT(stats.at("cubes_drawn").get<std::uint64_t>(), 0u);
    EXPECT_GT(stats.at("instances_entered").get<std::uint64_t>(), 0u);
    EXPECT_GT(coveredPixels(decodeImage(png)), 160u * 120u / 20);
}

// ------------------------------------------------------------------------------------------
// Bounded memory: a terrain of at least 8x the budget in triangle bytes.

TEST(BuildCommandTest, TerrainEightTimesTheBudgetBuildsWithinIt) {
    const fs::path dir = freshTestDir();
    constexpr std::uint64_t kBudget = 16 * kMiB;
    const fs::path scene = dir / "terrain.ffs";
    const ProcessResult built = build(
            dir, {"--generate", "terrain:triangles=2300000", "--memory-budget", "16MiB"}, scene);
    ASSERT_TRUE(exitedWith(built, 0)) << built.describe();
    RecordProperty("build_seconds", std::to_string(built.seconds));
    RecordProperty("max_rss_bytes", std::to_string(built.maxRssBytes));
    std::printf(
            "terrain:triangles=2300000 at 16 MiB built in %.1f s, ru_maxrss %llu MiB\n",
            built.seconds,
            static_cast<unsigned long long>(built.maxRssBytes / kMiB));
    const json report = readJsonFile(dir / "terrain.json");
    ASSERT_TRUE(report.is_object());
    // 60 bytes per PackedTriangle: the input alone is more than 8 budgets.
    EXPECT_GE(report.at("input_triangles").get<std::uint64_t>() * 60u, 8 * kBudget);
    EXPECT_EQ(report.at("memory_budget_bytes").get<std::uint64_t>(), kBudget);
    EXPECT_GT(report.at("chunks").get<std::uint64_t>(), 1u);
    EXPECT_LE(built.maxRssBytes, kBudget + 64 * kMiB);

    const ProcessResult checked = runFarfield({"check", scene.string()}, dir);
    EXPECT_TRUE(exitedWith(checked, 0)) << checked.describe();
}

// ------------------------------------------------------------------------------------------
// Format 2: built, verified by check down to every cluster; the runtime says it cannot draw it.

TEST(BuildCommandTest, FormatTwoIsCheckedAndDrawn) {
    const fs::path dir = freshTestDir();
    const fs::path scene = dir / "skull2.ffs";
    const ProcessResult built = build(dir, {(kData / "scanned/skull/skull.glb").string(), "--format", "2"}, scene);
    ASSERT_TRUE(exitedWith(built, 0)) << built.describe();
    const json report = readJsonFile(dir / "skull2.json");
    EXPECT_EQ(report.at("format_version").get<int>(), 2);
    EXPECT_GT(report.at("clusters").at("count").get<std::uint64_t>(), 0u);

    const ProcessResult checked = runFarfield({"check", "--json", scene.string()}, dir);
    ASSERT_TRUE(exitedWith(checked, 0)) << checked.describe();
    const json result = json::parse(checked.out);
    EXPECT_EQ(result.at("format_version").get<int>(), 2);
    EXPECT_EQ(result.at("hierarchy").at("triangles").get<std::uint64_t>(), report.at("stored_triangles").get<std::uint64_t>());
    EXPECT_EQ(result.at("hierarchy").at("nodes").get<std::uint64_t>(), report.at("nodes").get<std::uint64_t>());

    // Without a budget every frame waits for what it lacks: the first is complete, like a
    // mapped format 1 file's (its geometry is decoded by the cache, so it is not mapped).
    // Without occlusion culling, whatever the default: it would leave the skull's hidden
    // triangles undrawn (84 k of 100 k drawn).
    const ProcessResult rendered = runFarfield(
            {"render", scene.string(), "-o", (dir / "skull.png").string(), "--epsilon", "0", "--occlusion", "off",
             "--stats", (dir / "stats.json").string()},
            dir);
    ASSERT_TRUE(exitedWith(rendered, 0)) << rendered.describe();
    const json frame = readJsonFile(dir / "stats.json").at("frames").back();
    EXPECT_EQ(frame.at("nodes_deferred").get<std::uint64_t>(), 0u);
    EXPECT_EQ(frame.at("triangles_drawn").get<std::uint64_t>(), report.at("stored_triangles").get<std::uint64_t>());
    EXPECT_TRUE(fs::exists(dir / "skull.png"));

    // A GPU arena of a few pages, smaller than the frame: pages evicted within the frame that
    // uploaded them are decoded again on the render thread, and the image does not change.
    const ProcessResult small = runFarfield(
            {"render", scene.string(), "-o", (dir / "small.png").string(), "--epsilon", "0", "--gpu-budget", "1MiB",
             "--stats", (dir / "small.json").string()},
            dir);
    ASSERT_TRUE(exitedWith(small, 0)) << small.describe();
    const json smallFrame = readJsonFile(dir / "small.json").at("frames").back();
    EXPECT_EQ(smallFrame.at("nodes_deferred").get<std::uint64_t>(), 0u);
    EXPECT_GT(smallFrame.at("pages_decoded_on_draw").get<std::uint64_t>(), 0u);
    EXPECT_EQ(frame.at("pages_decoded_on_draw").get<std::uint64_t>(), 0u);
    EXPECT_EQ(differingPixels(decodeImage(dir / "skull.png"), decodeImage(dir / "small.png")), 0u);
}

// --cluster-nodes: from far enough that a leaf covers a few pixels, its cluster pieces are drawn
// as cubes instead of all its triangles; up close and at ε = 0 every triangle is still drawn.
TEST(BuildCommandTest, ClusterNodesLetTheCutStopInsideALeaf) {
    const fs::path dir = freshTestDir();
    const std::vector<std::string> terrain = {"--generate", "terrain:triangles=200000", "--format", "2"};
    std::vector<std::string> withNodes = terrain;
    withNodes.push_back("--cluster-nodes");
    ASSERT_TRUE(exitedWith(build(dir, terrain, dir / "leaves.ffs"), 0));
    ASSERT_TRUE(exitedWith(build(dir, withNodes, dir / "nodes.ffs"), 0));
    const json leaves = readJsonFile(dir / "leaves.json");
    const json nodes = readJsonFile(dir / "nodes.json");
    EXPECT_GT(nodes.at("nodes").get<std::uint64_t>(), 4 * leaves.at("nodes").get<std::uint64_t>());
    // Cluster nodes take their leaves from larger subtrees unless told otherwise.
    EXPECT_EQ(leaves.at("cluster_leaf_triangles").get<std::uint64_t>(), builder::kClusterLeafTriangles);
    // The terrain is placed once: it keeps the large leaves (HierarchyParams::leavesFor).
    EXPECT_EQ(leaves.at("smallest_cluster_leaf_triangles").get<std::uint64_t>(), builder::kClusterLeafTriangles);
    EXPECT_FALSE(leaves.at("cluster_nodes").get<bool>());
    EXPECT_EQ(nodes.at("cluster_leaf_triangles").get<std::uint64_t>(), builder::kClusterNodesLeafTriangles);
    EXPECT_TRUE(nodes.at("cluster_nodes").get<bool>());
    EXPECT_EQ(nodes.at("stored_triangles"), leaves.at("stored_triangles"));
    withNodes.push_back("--no-cluster-nodes"); // asking for both is refused
    EXPECT_FALSE(exitedWith(build(dir, withNodes, dir / "both.ffs"), 0));
    EXPECT_FALSE(fs::exists(dir / "both.ffs"));
    const ProcessResult checked = runFarfield({"check", (dir / "nodes.ffs").string()}, dir);
    EXPECT_TRUE(exitedWith(checked, 0)) << checked.describe();

    const auto frame = [&](const std::string& scene, const std::string& epsilon, const std::string& distance) {
        const std::string stem = scene + "-" + epsilon + "-" + distance;
        const ProcessResult r = runFarfield(
                {"render", (dir / (scene + ".ffs")).string(), "-o", (dir / (stem + ".png")).string(), "--epsilon",
                 epsilon, "--distance", distance, "--elevation", "60", "--stats", (dir / (stem + ".json")).string()},
                dir);
        EXPECT_TRUE(exitedWith(r, 0)) << r.describe();
        return readJsonFile(dir / (stem + ".json")).at("frames").back();
    };
    const std::uint64_t stored = nodes.at("stored_triangles").get<std::uint64_t>();
    EXPECT_EQ(frame("nodes", "0", "40").at("triangles_drawn").get<std::uint64_t>(), stored);
    EXPECT_EQ(frame("nodes", "1", "3").at("triangles_drawn").get<std::uint64_t>(), stored);
    // 40 radii away a leaf covers a few pixels, its pieces about one: format 2's plain leaves are
    // drawn whole, the pieces as cubes.
    const json far = frame("nodes", "1", "40");
    const json farLeaves = frame("leaves", "1", "40");
    EXPECT_GT(farLeaves.at("triangles_drawn").get<std::uint64_t>(), stored / 2);
    EXPECT_LT(far.at("triangles_drawn").get<std::uint64_t>() * 100, farLeaves.at("triangles_drawn").get<std::uint64_t>());
    EXPECT_GT(far.at("cubes_drawn").get<std::uint64_t>(), 10 * farLeaves.at("cubes_drawn").get<std::uint64_t>());
    const Result<runtime::ColorError> error =
            runtime::colorError(decodeImage(dir / "nodes-1-40.png"), decodeImage(dir / "nodes-0-40.png"));
    ASSERT_TRUE(error.isOk()) << error.status().message();
    EXPECT_GE(error->psnrSrgb, 40.0) << "the pieces' cubes against every triangle";
}

// ------------------------------------------------------------------------------------------
// Determinism: same input, same bytes.

TEST(BuildCommandTest, SameInputGivesByteIdenticalFiles) {
    const fs::path dir = freshTestDir();
    const std::vector<std::vector<std::string>> inputs = {
            {"--generate", "forest:trees=4"},
            {(kData / "static/CesiumMilkTruck/glTF-Binary/CesiumMilkTruck.glb").string()},
    };
    for (std::size_t i = 0; i < inputs.size(); ++i) {
        const std::string suffix = std::to_string(i) + ".ffs"; // no "a" + string: GCC 12 -Wrestrict
        const fs::path a = dir / ("a" + suffix);
        const fs::path b = dir / ("b" + suffix);
        const ProcessResult first = build(dir, inputs[i], a);
        const ProcessResult second = build(dir, inputs[i], b);
        ASSERT_TRUE(exitedWith(first, 0)) << first.describe();
        ASSERT_TRUE(exitedWith(second, 0)) << second.describe();
        const std::vector<unsigned char> bytesA = readBytes(a);
        const std::vector<unsigned char> bytesB = readBytes(b);
        ASSERT_EQ(bytesA.size(), bytesB.size()) << inputs[i][0];
        std::size_t firstDifference = 0;
        while (firstDifference < bytesA.size() &&
               bytesA[firstDifference] == bytesB[firstDifference])
            ++firstDifference;
        EXPECT_EQ(firstDifference, bytesA.size())
                << inputs[i][0] << ": first difference at byte " << firstDifference;
    }
}

// ------------------------------------------------------------------------------------------
// Bad input: refused with a message and exit code, never a signal, never an output file.

/** Files of ../shared/data/invalid that the importer accepts (see the builder's corpus test:
 *  their errors are in data farfield ignores). Every other file must be refused. */
const std::set<std::string> kInvalidButLoadable = {
        "gltf-validator/accessor_data/out_of_range_elements_uint16.gltf",
        "gltf-validator/accessor_data/invalid_elements_float.gltf",
        "gltf-validator/mesh_data/joints_weights_complex.gltf",
        "gltf-validator/mesh/morph_attribute_invalid_count.gltf",
        "gltf-validator/mesh/morph_unequal_targets_count.gltf",
        "gltf-validator/skin/ibm_invalid_count.gltf",
        "gltf-validator/skin/unresolved_joint.gltf",
        "gltf-validator/skin_data/invalid_ibm.gltf",
        "gltf-validator/animation/unresolved_sampler_input.gltf",
        "gltf-validator/animation/sampler_output_count_invalid.gltf",
        "gltf-validator/animation_data/invalid_input_values.gltf",
        "tinygltf/tests/issue-416.gltf",
        "tinygltf/tests/issue-492.glb",
        "tinygltf/models/regression/zero-sized-bin-chunk-issue-440.glb",
        "tinygltf/models/regression/unassigned-skeleton.gltf",
};

TEST(BuildCommandTest, EveryInvalidGltfIsRefusedCleanlyOrBuildsAValidFile) {
    const fs::path dir = freshTestDir();
    std::vector<fs::path> files;
    for (const auto& entry : fs::recursive_directory_iterator(kData / "invalid")) {
        const std::string ext = entry.path().extension().string();
        if (entry.is_regular_file() && (ext == ".gltf" || ext == ".glb"))
            files.push_back(entry.path());
    }
    std::sort(files.begin(), files.end());
    ASSERT_EQ(files.size(), 59u); // the corpus of invalid/expected.tsv; guards against it moving

    std::size_t loaded = 0;
    for (const fs::path& file : files) {
        const std::string relative = fs::relative(file, kData / "invalid").string();
        SCOPED_TRACE(relative);
        const fs::path output = dir / "out.ffs";
        const ProcessResult r = build(dir, {file.string()}, output);
        ASSERT_FALSE(r.signaled) << r.describe();
        ASSERT_TRUE(r.exited) << r.describe();
        if (r.exitCode == 0) {
            EXPECT_TRUE(kInvalidButLoadable.count(relative)) << "must be refused but built";
            const ProcessResult checked = runFarfield({"check", output.string()}, dir);
            EXPECT_TRUE(exitedWith(checked, 0)) << checked.describe();
            ++loaded;
        } else {
            EXPECT_EQ(r.exitCode, 1) << r.describe(); // bad data, not a bad command line
            EXPECT_EQ(r.err.rfind("farfield build: ", 0), 0u) << r.describe();
            EXPECT_GT(r.err.size(), 40u) << "message too short to help: " << r.err;
            EXPECT_FALSE(fs::exists(output)) << "a refused build left an output file";
        }
        for (const std::string& name : leftovers(dir)) {
            ADD_FAILURE() << "left behind " << name;
            fs::remove_all(dir / name);
        }
        fs::remove(output);
    }
    EXPECT_GT(loaded, 0u);
}

TEST(BuildCommandTest, TruncatedGlbIsRefused) {
    const fs::path dir = freshTestDir();
    const std::vector<unsigned char> glb =
            readBytes(kData / "static/CesiumMilkTruck/glTF-Binary/CesiumMilkTruck.glb");
    ASSERT_GT(glb.size(), 1000u);
    for (const std::size_t size :
         {std::size_t{0},
          std::size_t{11},
          std::size_t{20},
          std::size_t{100},
          glb.size() / 2,
          glb.size() - 1}) {
        SCOPED_TRACE("truncated to " + std::to_string(size) + " bytes");
        const fs::path truncated = dir / "truncated.glb";
        writeBytes(
                truncated,
                std::vector<unsigned char>(
                        glb.begin(), glb.begin() + static_cast<std::ptrdiff_t>(size)));
        const ProcessResult r = build(dir, {truncated.string()}, dir / "out.ffs");
        EXPECT_TRUE(exitedWith(r, 1)) << r.describe();
        EXPECT_EQ(r.err.rfind("farfield build: ", 0), 0u) << r.describe();
        EXPECT_FALSE(fs::exists(dir / "out.ffs"));
    }
}

TEST(BuildCommandTest, MissingOutputDirectoryIsAnErrorAndCreatesNothing) {
    const fs::path dir = freshTestDir();
    const fs::path missing = dir / "no" / "such" / "directory";
    const ProcessResult r = build(dir, {"--generate", "forest:trees=1"}, missing / "scene.ffs");
    EXPECT_TRUE(r.exited && r.exitCode != 0) << r.describe();
    EXPECT_NE(r.err.find(missing.string()), std::string::npos) << r.describe();
    EXPECT_FALSE(fs::exists(dir / "no")) << "build created the missing output directory";
}

TEST(BuildCommandTest, MemoryBudgetBelowTheMinimumIsRefused) {
    const fs::path dir = freshTestDir();
    const ProcessResult r =
            build(dir, {"--generate", "forest:trees=1", "--memory-budget", "1MiB"}, dir / "x.ffs");
    EXPECT_TRUE(exitedWith(r, 2)) << r.describe();
    EXPECT_NE(r.err.find("--memory-budget"), std::string::npos) << r.describe();
    EXPECT_NE(r.err.find("minimum"), std::string::npos) << r.describe();
    EXPECT_FALSE(fs::exists(dir / "x.ffs"));
    EXPECT_EQ(leftovers(dir), std::vector<std::string>{});
}

TEST(BuildCommandTest, BadGeneratorSpecsExitWithUsageErrors) {
    const fs::path dir = freshTestDir();
    const std::vector<std::pair<std::string, std::string>> cases = {
            {"nosuch", "unknown generator 'nosuch'"},
            {"forest:trees=3", "power of 4"},
            {"forest:trees=abc", "'abc'"},
            {"forest:leaves=7", "unknown parameter 'leaves'"},
            {"terrain:triangles=-5", "triangles"},
    };
    for (const auto& [spec, message] : cases) {
        const ProcessResult r = build(dir, {"--generate", spec}, dir / "x.ffs");
        EXPECT_TRUE(exitedWith(r, 2)) << r.describe();
        EXPECT_NE(r.err.find(message), std::string::npos) << r.describe();
        EXPECT_FALSE(fs::exists(dir / "x.ffs"));
    }
    const ProcessResult both =
            build(dir, {"--generate", "forest:trees=1", "input.gltf"}, dir / "x.ffs");
    EXPECT_TRUE(exitedWith(both, 2)) << both.describe();
    const ProcessResult neither = build(dir, {}, dir / "x.ffs");
    EXPECT_TRUE(exitedWith(neither, 2)) << neither.describe();
}

// ------------------------------------------------------------------------------------------
// --help

TEST(CliHelpTest, EveryVerbDocumentsItsFlags) {
    const fs::path dir = freshTestDir();
    const std::vector<std::pair<std::string, std::vector<std::string>>> verbs = {
            {"build",
             {"--generate",
              "--output",
              "--memory-budget",
              "--page-size",
              "--threads",
              "--bake-resolution",
              "--bake-inner",
              "--cube-cost",
              "--large-triangle-tolerance",
              "--max-depth",
              "--report",
              "--temp-dir",
              "--quiet",
              "forest",
              "terrain",
              "molecule",
              "blinds"}},
            {"render",
             {"--output",
              "--size",
              "--epsilon",
              "--method",
              "--supersample",
              "--frames",
              "--stats",
              "--background",
              "--gpu-budget",
              "--coverage-alpha",
              "--camera",
              "--eye",
              "--target",
              "--up",
              "--fov",
              "--distance",
              "--azimuth",
              "--elevation"}},
            {"check", {"--json"}},
            {"bench", {"--help"}},
    };
    for (const auto& [verb, flags] : verbs) {
        const ProcessResult r = runFarfield({verb, "--help"}, dir);
        EXPECT_TRUE(exitedWith(r, 0)) << r.describe();
        EXPECT_NE(r.out.find("Usage: farfield " + verb), std::string::npos) << r.describe();
        for (const std::string& flag : flags)
            EXPECT_NE(r.out.find(flag), std::string::npos)
                    << verb << " --help does not mention " << flag;
    }
    const ProcessResult top = runFarfield({"--help"}, dir);
    EXPECT_TRUE(exitedWith(top, 0)) << top.describe();
    for (const auto& verb : verbs)
        EXPECT_NE(top.out.find(verb.first), std::string::npos)
                << "farfield --help does not list " << verb.first;
    const ProcessResult none = runFarfield({}, dir);
    EXPECT_TRUE(none.exited && none.exitCode != 0) << none.describe();
}

} // namespace
} // namespace ff::viewer::test
