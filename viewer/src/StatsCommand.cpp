#include "Commands.h"
#include "FrameFlags.h"
#include "OutputFile.h"

#include <ff/bench/SceneStats.h>
#include <ff/runtime/Units.h>
#include <ff/storage/HierarchyCheck.h>
#include <ff/storage/SceneFile.h>

#include <nlohmann/json.hpp>

#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace ff::viewer {

namespace {

// The statistics live with the other measurements, in ff_bench.
using namespace ff::bench;

struct StatsArgs {
    std::string scene;
    std::string json;  ///< file to write, "-" = stdout
    std::string input; ///< glTF file or generator spec to compare against
    std::uint64_t inputBytes = 0;
    CLI::Option* inputBytesOption = nullptr;
    bool paths = false;
    std::vector<std::string> pathKinds = {"orbit", "flythrough"};
    std::int64_t frames = 60;
    float epsilon = 1.0f;
    std::string size = "640x480";
};

// The input to compare with: --input-bytes, else --input, else the scene's own "source" (a glTF
// path as given to build, or generate:SPEC). A source that cannot be found leaves it unknown.
Result<std::optional<InputSize>> resolveInput(const StatsArgs& args, const SceneStats& stats) {
    if (args.inputBytesOption->count() > 0) {
        InputSize input;
        input.bytes = args.inputBytes;
        input.what = "given with --input-bytes";
        return std::optional<InputSize>(input);
    }
    std::string source = args.input.empty() ? stats.source : args.input;
    if (source.rfind("generate:", 0) == 0)
        source = source.substr(9);
    if (source.empty())
        return std::optional<InputSize>();
    const std::string ext = std::filesystem::path(source).extension().string();
    if (ext == ".gltf" || ext == ".glb") {
        if (args.input.empty() && !std::filesystem::exists(source))
            return std::optional<InputSize>(); // built elsewhere: not an error
        FF_ASSIGN_OR_RETURN(const InputSize input, measureGltfInput(source));
        return std::optional<InputSize>(input);
    }
    FF_ASSIGN_OR_RETURN(const InputSize input, measureGeneratorInput(source));
    return std::optional<InputSize>(input);
}

double percent(std::uint64_t part, std::uint64_t whole) {
    return whole == 0 ? 0.0 : 100.0 * static_cast<double>(part) / static_cast<double>(whole);
}

void printText(const SceneStats& s) {
    std::printf(
            "%s: %s in %llu pages of %s",
            s.path.c_str(),
            runtime::formatBytes(s.fileBytes).c_str(),
            static_cast<unsigned long long>(s.pageCount),
            runtime::formatBytes(s.pageSize).c_str());
    if (s.input)
        std::printf(
                ", %.3gx the input (%s: %s)",
                static_cast<double>(s.fileBytes) /
                        static_cast<double>(std::max<std::uint64_t>(s.input->bytes, 1)),
                s.input->what.c_str(),
                runtime::formatBytes(s.input->bytes).c_str());
    std::printf("\n");
    std::printf(
            "nodes      %llu (%llu instance level, %llu in prototypes): %llu instance, %llu inner "
            "cells, "
            "%llu leaves (%llu empty, %llu with < 8 triangles); %.4f nodes per stored triangle\n",
            static_cast<unsigned long long>(s.nodes),
            static_cast<unsigned long long>(s.instanceLevelNodes),
            static_cast<unsigned long long>(s.prototypeNodes),
            static_cast<unsigned long long>(s.instanceNodes),
            static_cast<unsigned long long>(s.innerCells),
            static_cast<unsigned long long>(s.leafCells),
            static_cast<unsigned long long>(s.emptyLeaves),
            static_cast<unsigned long long>(s.smallLeaves),
            s.storedTriangles
                    ? static_cast<double>(s.nodes) / static_cast<double>(s.storedTriangles)
                    : 0.0);
    std::printf(
            "triangles  %llu stored, %llu instanced; %llu prototypes, %llu instances\n",
            static_cast<unsigned long long>(s.storedTriangles),
            static_cast<unsigned long long>(s.instancedTriangles),
            static_cast<unsigned long long>(s.prototypes),
            static_cast<unsigned long long>(s.instances));
    std::printf(
            "pages      1 header, %llu nodes (%llu under 1/4 full), %llu geometry (%llu under 1/4 "
            "full), "
            "%llu table, %llu unreferenced\n",
            static_cast<unsigned long long>(s.nodePages),
            static_cast<unsigned long long>(s.sparseNodePages),
            static_cast<unsigned long long>(s.geometryPages),
            static_cast<unsigned long long>(s.sparseGeometryPages),
            static_cast<unsigned long long>(s.tablePages),
            static_cast<unsigned long long>(s.unreferencedPages));
    const struct {
        const char* name;
        std::uint64_t bytes;
    } rows[] = {
            {"node records", s.nodeRecordBytes},
            {"  of which cubes", s.cubeBytes},
            {"triangles", s.triangleBytes},
            {"instance transforms", s.instanceRecordBytes},
            {"prototype records", s.prototypeRecordBytes},
            {"metadata", s.metadataBytes},
            {"header + sections", s.headerBytes},
            {"page trailers", s.trailerBytes},
            {"slack: header page", s.headerSlack},
            {"slack: nodes pages", s.nodeSlack},
            {"slack: geometry pages", s.geometrySlack},
            {"slack: table pages", s.tableSlack},
            {"unreferenced pages", s.unreferencedBytes},
    };
    for (const auto& row : rows)
        std::printf(
                "  %-22s %12llu B %6.2f%%\n",
                row.name,
                static_cast<unsigned long long>(row.bytes),
                percent(row.bytes, s.fileBytes));
    if (s.cubes) {
        const CubeUsage& c = *s.cubes;
        std::printf(
                "cubes      %llu of %llu nodes with a cube drawn at least once over %zu paths x "
                "%lld frames "
                "(%dx%d, eps %g); %llu never drawn (%s: %llu instance, %llu inner, %llu leaf)\n",
                static_cast<unsigned long long>(c.nodesDrawn),
                static_cast<unsigned long long>(c.nodesWithCube),
                c.paths.size(),
                static_cast<long long>(c.framesPerPath),
                c.width,
                c.height,
                static_cast<double>(c.epsilonPixels),
                static_cast<unsigned long long>(c.neverDrawn),
                runtime::formatBytes(c.neverDrawnBytes).c_str(),
                static_cast<unsigned long long>(c.neverDrawnInstance),
                static_cast<unsigned long long>(c.neverDrawnInner),
                static_cast<unsigned long long>(c.neverDrawnLeaf));
    }
}

/** Format 2: what its hierarchy holds and which representations its cells keep, verified and
 *  walked as `check` does (every page's checksum, then storage::checkHierarchyV2). Why a cell kept none is the build's to say
 *  (its report's stand_ins and splats). */
Result<nlohmann::json> statsV2(const StatsArgs& args, const storage::SceneFile& scene) {
    if (args.paths)
        return Status(ErrorCode::Unsupported, "--paths reads format version 1 files");
    FF_RETURN_IF_ERROR(scene.verifyAll());
    FF_ASSIGN_OR_RETURN(const storage::HierarchySummary h, storage::checkHierarchyV2(scene, scene.source()));
    const std::uint64_t fileBytes = std::filesystem::file_size(args.scene);
    return nlohmann::json{
            {"scene", args.scene},
            {"format_version", storage::kFormatVersion2},
            {"file_bytes", fileBytes},
            {"pages", scene.pageCount()},
            {"page_size", scene.pageSize()},
            {"nodes", h.nodes},
            {"clusters", h.clusters},
            {"cluster_pages", h.clusterPages},
            {"triangles", h.triangles},
            {"bytes_per_triangle",
             h.triangles == 0 ? 0.0 : static_cast<double>(fileBytes) / static_cast<double>(h.triangles)},
            {"representations",
             {{"records", h.representations},
              {"simplified", {{"nodes", h.standIns}, {"triangles", h.standInTriangles}}},
              {"splats", {{"nodes", h.splatSets}, {"points", h.splats}, {"triangles", h.splatTriangles}}}}}};
}

void printTextV2(const nlohmann::json& s) {
    const auto count = [&](const nlohmann::json& j) { return static_cast<unsigned long long>(j.get<std::uint64_t>()); };
    const nlohmann::json& r = s["representations"];
    std::printf(
            "%s: format 2, %s in %llu pages of %s, %.2f bytes a triangle\n",
            s["scene"].get<std::string>().c_str(),
            runtime::formatBytes(s["file_bytes"].get<std::uint64_t>()).c_str(),
            count(s["pages"]),
            runtime::formatBytes(s["page_size"].get<std::uint64_t>()).c_str(),
            s["bytes_per_triangle"].get<double>());
    std::printf(
            "nodes      %llu, %llu triangles in %llu clusters (%llu cluster pages)\n",
            count(s["nodes"]),
            count(s["triangles"]),
            count(s["clusters"]),
            count(s["cluster_pages"]));
    std::printf(
            "stand-ins  %llu cells keep a simplified copy (%llu triangles), %llu keep splats (%llu "
            "splats, %llu triangles); every cell has its cube and its own payload\n",
            count(r["simplified"]["nodes"]),
            count(r["simplified"]["triangles"]),
            count(r["splats"]["nodes"]),
            count(r["splats"]["points"]),
            count(r["splats"]["triangles"]));
}

int runStats(const StatsArgs& args) {
    auto jsonFile = reserveIfNamed(args.json == "-" ? std::string() : args.json, OutputKind::Text);
    if (!jsonFile)
        return reportError("stats", jsonFile.status().withContext("--json"));
    auto scene = storage::SceneFile::open(args.scene);
    if (!scene)
        return reportError("stats", scene.status().withContext(args.scene));
    if ((*scene)->formatVersion() == storage::kFormatVersion2) {
        Result<nlohmann::json> v2 = statsV2(args, **scene);
        if (!v2)
            return reportError("stats", v2.status().withContext(args.scene));
        if (args.json == "-") {
            std::printf("%s\n", v2->dump(2).c_str());
            return 0;
        }
        printTextV2(*v2);
        if (*jsonFile)
            if (const Status written = (*jsonFile)->commitText(v2->dump(2) + "\n"); !written)
                return reportError("stats", written);
        return 0;
    }
    Result<SceneStats> stats = collectSceneStats(**scene);
    if (!stats)
        return reportError("stats", stats.status().withContext(args.scene));
    Result<std::optional<InputSize>> input = resolveInput(args, *stats);
    if (!input)
        return reportError("stats", input.status().withContext("--input"));
    stats->input = *input;
    if (args.paths) {
        auto size = runtime::parseImageSize(args.size);
        if (!size)
            return reportError("stats", size.status().withContext("--size"));
        CubeUsageOptions options;
        options.paths = args.pathKinds;
        options.framesPerPath = args.frames;
        options.epsilonPixels = args.epsilon;
        options.width = size->x;
        options.height = size->y;
        if (Status status = measureCubeUsage(**scene, options, *stats); !status)
            return reportError("stats", status.withContext(args.scene));
    }
    if (args.json == "-") {
        std::printf("%s\n", stats->toJson().dump(2).c_str());
        return 0;
    }
    printText(*stats);
    if (*jsonFile) {
        if (const Status written = (*jsonFile)->commitText(stats->toJson().dump(2) + "\n"); !written)
            return reportError("stats", written);
    }
    return 0;
}

} // namespace

CommandRunner addStatsCommand(CLI::App& app) {
    auto args = std::make_shared<StatsArgs>();
    CLI::App* cmd = app.add_subcommand(
            "stats",
            "What a scene file holds: bytes per representation against the input, nodes per "
            "triangle, "
            "page fill; with --paths, which color cubes the standard camera paths draw");
    cmd->add_option("scene", args->scene, "Scene file (.ffs)")->required();
    cmd->add_option(
            "--json",
            args->json,
            "Also write the statistics as JSON to this file ('-': JSON on stdout only)");
    CLI::Option* inputOption = cmd->add_option(
            "--input",
            args->input,
            "Input to compare with: a .gltf/.glb file or a generator spec (default: the scene's "
            "recorded source, if it can be found)");
    args->inputBytesOption = cmd->add_option(
            "--input-bytes", args->inputBytes, "Input size in bytes, given directly");
    cmd->add_flag(
            "--paths",
            args->paths,
            "Select (no drawing, every page resident) along camera paths fitted to the scene and "
            "count "
            "the nodes whose cube was drawn");
    cmd->add_option(
               "--path-kinds", args->pathKinds, "Paths for --paths: orbit, flythrough, teleports")
            ->check(CLI::IsMember({"orbit", "flythrough", "teleports"}))
            ->capture_default_str();
    cmd->add_option("--frames", args->frames, "Frames per path for --paths")
            ->check(CLI::Range(1, 100000))
            ->capture_default_str();
    addEpsilonOption(*cmd, args->epsilon)->description(std::string("With --paths: ") + kEpsilonHelp);
    cmd->add_option("--size", args->size, "Viewport WIDTHxHEIGHT for --paths")
            ->capture_default_str();
    inputOption->excludes(args->inputBytesOption);
    return [args]() { return runStats(*args); };
}

} // namespace ff::viewer
