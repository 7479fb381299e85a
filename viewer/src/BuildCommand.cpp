#include "Commands.h"
#include "OutputFile.h"
#include "ProgressBar.h"
#include "SceneInput.h"

#include <ff/builder/Generators.h>
#include <ff/builder/SceneBuilder.h>
#include <ff/runtime/Units.h>

#include <glm/gtc/matrix_transform.hpp>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <string>

namespace ff::viewer {

namespace {

struct BuildArgs {
    std::string input;
    std::string generate;
    std::string output;
    std::string memoryBudget = "1GiB";
    std::string pageSize = "auto";
    unsigned threads = 0;
    int bakeResolution = 8;
    std::string bakeInner = "composite";
    float cubeCost = 6.0f;
    float largeTriangleTolerance = 1.0f;
    int maxDepth = 20;
    std::string decomposition = "octree";
    builder::DecompositionParams split;
    std::string offset = "0,0,0";
    double scale = 1.0;
    std::string report;
    std::string tempDirectory;
    std::string spill = "compact";
    unsigned format = 2;
    std::optional<std::uint64_t> clusterLeafTriangles; ///< unset: HierarchyParams::leavesFor()
    bool clusterNodes = false;   ///< --cluster-nodes: every prototype placed once
    bool noClusterNodes = false; ///< --no-cluster-nodes: none; neither: by size
    bool standIns = false;
    int splatSpacing = 0;
    std::string standInChoice = "measured";
    bool quiet = false;
};

std::string generatorHelp() {
    std::string text = "\nGenerators (--generate NAME:key=value,...):\n";
    for (const builder::GeneratorInfo& g : builder::generatorCatalog()) {
        text += "  " + g.name + "  " + g.summary + "\n";
        for (const auto& [key, meaning] : g.params)
            text += "      " + key + "  " + meaning + "\n";
    }
    return text;
}

int runBuild(const BuildArgs& args) {
    if (args.input.empty() == args.generate.empty())
        return reportError("build", Status(ErrorCode::InvalidArgument, "give either an input glTF file or --generate"));
    builder::BuildOptions options;
    auto budget = runtime::parseByteSize(args.memoryBudget);
    if (!budget)
        return reportError("build", budget.status().withContext("--memory-budget"));
    std::optional<std::uint32_t> pageSize; // auto
    if (args.pageSize != "auto") {
        auto bytes = runtime::parseByteSize(args.pageSize);
        if (!bytes)
            return reportError("build", bytes.status().withContext("--page-size"));
        pageSize = static_cast<std::uint32_t>(std::min<std::uint64_t>(*bytes, 0xFFFFFFFFu));
    }
    if (args.bakeInner != "composite" && args.bakeInner != "direct")
        return reportError("build", Status(ErrorCode::InvalidArgument, "--bake-inner must be composite or direct"));
    options.memoryBudgetBytes = *budget;
    options.pageSize = pageSize;
    options.threads = args.threads;
    options.tempDirectory = args.tempDirectory;
    const std::optional<builder::SpillCodec> spill = builder::parseSpillCodec(args.spill);
    if (!spill)
        return reportError("build", Status(ErrorCode::InvalidArgument, "--spill must be compact or raw"));
    options.spillCodec = *spill;
    options.formatVersion = args.format;
    options.hierarchy.clusterLeafTriangles = args.clusterLeafTriangles;
    if (args.clusterNodes || args.noClusterNodes)
        options.hierarchy.clusterNodes = args.clusterNodes;
    options.hierarchy.standIns = args.standIns;
    options.hierarchy.splatSpacing = args.splatSpacing;
    options.hierarchy.measureStandIns = args.standInChoice == "measured";
    options.hierarchy.bakeResolution = args.bakeResolution;
    options.hierarchy.bakeInnerDirect = args.bakeInner == "direct";
    options.hierarchy.cubeCost = args.cubeCost;
    options.hierarchy.largeTriangleTolerance = args.largeTriangleTolerance;
    options.hierarchy.maxDepth = args.maxDepth;
    const std::optional<builder::Decomposition> decomposition = builder::parseDecomposition(args.decomposition);
    if (!decomposition)
        return reportError(
                "build", Status(ErrorCode::InvalidArgument, "--decomposition must be octree, dbvd, phbvo, balanced or orsd"));
    options.hierarchy.decomposition = *decomposition;
    options.hierarchy.split = args.split;
    auto offset = runtime::parseDVec3(args.offset);
    if (!offset)
        return reportError("build", offset.status().withContext("--offset"));
    if (!(std::isfinite(args.scale) && args.scale > 0.0))
        return reportError("build", Status(ErrorCode::InvalidArgument, "--scale must be a positive number"));
    options.placement = glm::translate(glm::dmat4(1.0), *offset) * glm::scale(glm::dmat4(1.0), glm::dvec3(args.scale));
    ProgressBar progress;
    if (!args.quiet)
        options.progress = [&progress](const builder::BuildProgress& p) { progress.update(p.phase, p.done, p.total); };

    // A mistyped -o must not create directories (the builder makes its spill folder beside the
    // output, creating parents): the output's directory has to exist already.
    const std::filesystem::path outputDirectory = std::filesystem::path(args.output).parent_path();
    std::error_code directoryError;
    if (!outputDirectory.empty() && !std::filesystem::is_directory(outputDirectory, directoryError))
        return reportError(
                "build",
                Status(ErrorCode::NotFound,
                       "output directory " + outputDirectory.string() + " does not exist"));
    auto reportFile = reserveIfNamed(args.report, OutputKind::Text);
    if (!reportFile)
        return reportError("build", reportFile.status().withContext("--report"));
    auto sceneBuilder = builder::SceneBuilder::create(args.output, options);
    if (!sceneBuilder)
        return reportError("build", sceneBuilder.status());
    if (!args.quiet)
        progress.update("scan", 0, 0);
    auto input = feedScene(args.input, args.generate, options.placement, **sceneBuilder);
    if (!input)
        return reportError("build", input.status());
    // The metadata section carries the source and its cameras.
    auto report = [&]() {
        (*sceneBuilder)->setMetadataJson(input->metadataJson);
        return (*sceneBuilder)->finish();
    }();
    progress.finish();
    if (!report)
        return reportError("build", report.status());

    nlohmann::json json = nlohmann::json::parse(builder::buildReportJson(*report));
    json["source"] = input->source;
    json["output"] = args.output;
    json["declared_triangles"] = input->declaredTriangles;
    json["warnings"] = input->warnings;
    if (*reportFile) {
        if (const Status written = (*reportFile)->commitText(json.dump(2) + "\n"); !written)
            return reportError("build", written.withContext("--report"));
    }
    if (!args.quiet) {
        for (const std::string& w : input->warnings)
            std::fprintf(stderr, "warning: %s\n", w.c_str());
        std::fprintf(stderr,
                     "built %s: %llu triangles drawn (%llu stored), %u prototypes, %llu instances, %llu nodes, "
                     "%s in %s pages%s, %.2f s, peak RSS %s\n",
                     args.output.c_str(), static_cast<unsigned long long>(report->instancedTriangles),
                     static_cast<unsigned long long>(report->storedTriangles), report->prototypes,
                     static_cast<unsigned long long>(report->instances), static_cast<unsigned long long>(report->nodes),
                     runtime::formatBytes(report->fileBytes).c_str(), runtime::formatBytes(report->pageSize).c_str(),
                     report->pageSizeAuto ? " (auto)" : "", json["total_seconds"].get<double>(),
                     runtime::formatBytes(report->peakRssBytes).c_str());
        if (report->droppedNonFinite + report->droppedDegenerate > 0)
            std::fprintf(stderr, "dropped %llu triangles with non-finite positions and %llu with zero area\n",
                         static_cast<unsigned long long>(report->droppedNonFinite),
                         static_cast<unsigned long long>(report->droppedDegenerate));
    }
    return 0;
}

} // namespace

CommandRunner addBuildCommand(CLI::App& app) {
    auto args = std::make_shared<BuildArgs>();
    CLI::App* cmd = app.add_subcommand("build", "Build a scene file (.ffs) from glTF or a generator, out of core");
    cmd->footer(generatorHelp());
    cmd->add_option("input", args->input, "Input glTF 2.0 file (.gltf or .glb)");
    cmd->add_option("--generate", args->generate, "Procedural scene instead of a file, e.g. forest:trees=16384");
    cmd->add_option("-o,--output", args->output, "Output scene file")->required();
    cmd->add_option("--memory-budget", args->memoryBudget, "Peak memory for building (e.g. 512MiB, 2GiB)")->capture_default_str();
    cmd->add_option("--page-size", args->pageSize, "Page size, a power of two from 4KiB to 16MiB, or auto: fitted to the scene, up to 64KiB (docs/methods.md)")->capture_default_str();
    cmd->add_option("--threads", args->threads, "Worker threads (0 = all cores)")->capture_default_str();
    cmd->add_option("--bake-resolution", args->bakeResolution, "Samples per cube face edge")->capture_default_str();
    cmd->add_option("--bake-inner", args->bakeInner, "Inner-node cubes: composite (Fig. 3) or direct from geometry")->capture_default_str();
    cmd->add_option("--cube-cost", args->cubeCost, "Triangles one drawn color cube costs (subdivision rule)")->capture_default_str();
    cmd->add_option("--large-triangle-tolerance", args->largeTriangleTolerance,
                    "Triangles larger than this x their cell stay at the inner node")->capture_default_str();
    cmd->add_option("--max-depth", args->maxDepth, "Deepest octree level")->capture_default_str();
    cmd->add_option("--decomposition", args->decomposition,
                    "How the hierarchy splits (docs/methods.md §10): octree (cost rule), dbvd (cube-like slabs of "
                    "the largest side), phbvo (binned-SAH bounding volumes), balanced (median planes), orsd "
                    "(relevant cells of a voxel grid; the isosurface generator only)")
            ->capture_default_str();
    builder::DecompositionParams& split = args->split;
    cmd->add_option("--min-triangles", split.minTriangles, "dbvd: an entity this small is a leaf")->capture_default_str();
    cmd->add_option("--min-size", split.minSize, "dbvd: an entity whose largest side is this short is a leaf (0: none)")
            ->capture_default_str();
    cmd->add_option("--plane-shift", split.planeShift,
                    "dbvd: how far a split plane may move to cut fewer triangles, share of a slab (0-0.45)")
            ->capture_default_str();
    cmd->add_option("--max-triangles", split.maxTriangles,
                    "phbvo: Max_Triangles_Per_Entity; balanced: tri_max")->capture_default_str();
    cmd->add_option("--tri-min", split.balancedMinTriangles, "balanced: fewest triangles a child gets")->capture_default_str();
    cmd->add_option("--arity", split.arity, "phbvo: children per node, 2 (binary) or 4 (collapsed)")
            ->check(CLI::IsMember({2u, 4u}))
            ->capture_default_str();
    cmd->add_option("--relevant-cells", split.relevantCells, "orsd: a block with more relevant cells splits")
            ->capture_default_str();
    cmd->add_option("--decomposition-depth", split.maxDepth, "dbvd/phbvo/balanced/orsd: Max_Decomposition_Depth")
            ->check(CLI::Range(1, 64))
            ->capture_default_str();
    cmd->add_option("--offset", args->offset, "Moves the input by x,y,z in the world (after --scale)")->capture_default_str();
    cmd->add_option("--scale", args->scale, "Scales the input about the world origin")->capture_default_str();
    cmd->add_option("--report", args->report, "Write the JSON build report here");
    cmd->add_option("--temp-dir", args->tempDirectory, "Directory for spill files (default: beside the output)");
    cmd->add_option("--spill", args->spill,
                    "How spill files store triangles: compact (lossless vertex codec: 2.5x fewer bytes on a terrain, a little slower) or raw")
            ->check(CLI::IsMember({"compact", "raw"}))
            ->capture_default_str();
    cmd->add_option("--format", args->format,
                    "Scene file format: 2 (compact clusters and 48-byte records, storage/FORMAT.md; drawn through "
                    "the page cache, which decodes its clusters) or 1 (96-byte records and 60-byte triangles; to "
                    "be refused)")
            ->check(CLI::IsMember({1u, 2u}))
            ->capture_default_str();
    cmd->add_option("--cluster-leaf-triangles", args->clusterLeafTriangles,
                    "--format 2: subtrees of at most this many triangles become one leaf of whole clusters (0: keep the "
                    "leaves); default 4096, 65536 with cluster nodes, and 16 in a prototype placed more than once "
                    "(its whole leaves are drawn in every placement in view)");
    CLI::Option* clusterNodes = cmd->add_flag(
            "--cluster-nodes", args->clusterNodes,
            "--format 2: give each leaf a tree of nodes down to pieces of about a cluster, each with its own bounds "
            "and cube, so the cut can stop inside a leaf: far views draw far fewer triangles, for 0.6-1 byte a "
            "triangle more (docs/results, \"Cluster nodes\"); default: only in prototypes placed once with more "
            "than 2^23 triangles");
    cmd->add_flag("--no-cluster-nodes", args->noClusterNodes,
                  "--format 2: no cluster nodes, whatever a prototype's size (its leaves drawn whole)")
            ->excludes(clusterNodes);
    cmd->add_flag("--stand-ins", args->standIns,
                  "--format 2: give cells a simplified copy of their subtree (meshoptimizer, borders locked), drawn "
                  "instead of it where its error is below --epsilon pixels (docs/methods.md, \"Stand-ins\")");
    cmd->add_option("--splats", args->splatSpacing,
                    "--format 2: give cells point splats standing in for their subtree, spaced at 1/N of the cell's "
                    "largest side (8-16; Wand & Strasser), drawn where their error is below --epsilon pixels; with "
                    "--stand-ins, a cell keeps the kind --stand-in-choice picks (docs/methods.md, \"Splats\")")
            ->check(CLI::Range(1, 64));
    cmd->add_option("--stand-in-choice", args->standInChoice,
                    "--format 2 with --stand-ins or --splats: measured (default) draws each candidate and the geometry it "
                    "stands for from the cell's six sides, raises its error where they differ and keeps the one that "
                    "pays best; rule keeps a simplified copy where one reduces, else splats (docs/methods.md, "
                    "\"Choosing per cell\")")
            ->check(CLI::IsMember({"measured", "rule"}));
    cmd->add_flag("-q,--quiet", args->quiet, "No progress or summary on stderr");
    return [args]() { return runBuild(*args); };
}

} // namespace ff::viewer
