#pragma once

// The external-memory builder. Architecture, in the order build() runs it:
//
//   scan            sources push prototypes, triangles and instances through ISceneSink; the
//                   triangles are validated (NaN, zero area: dropped and counted) and spilled to
//                   one run file per prototype, so nothing is held whole.
//   partition       per prototype: if it fits the memory budget it is one chunk; otherwise a
//                   counting pass over its run file picks octree cells that fit (chunks) and a
//                   distribution pass writes each chunk's triangles to a file of its own.
//   buildHierarchy  each chunk is loaded, built into an octree (cost rule, large-triangle
//                   tolerance) with color cubes, and encoded into pages, on worker
//                   threads; results are written in chunk order so the output is deterministic.
//                   The cells above the chunks (and the large triangles that live there) form
//                   the prototype's top tree. Then the instance level: an octree over instance
//                   bounds whose leaves point at prototypes, with cubes baked from the
//                   transformed prototype cubes.
//   writePages      prototype, instance and metadata sections, header; fsync and rename.
//
// Memory: peak usage stays within BuildOptions::memoryBudgetBytes plus a small fixed overhead:
// chunks are sized to (budget / worker threads), and spill buffers take a fixed share.

#include <ff/builder/HierarchyParams.h>
#include <ff/builder/SceneSink.h>
#include <ff/builder/SpillCodec.h>
#include <ff/storage/SceneFormat.h>
#include <ff/storage/Status.h>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace ff::builder {

/** Progress of a long phase, for a terminal progress bar. Called on the building thread. */
struct BuildProgress {
    std::string phase; ///< "scan", then "hierarchy" and, within a chunked prototype, "count",
                       ///< "partition", "chunks", "layout"; then "instances", "write"
    std::uint64_t done = 0;
    std::uint64_t total = 0; ///< 0 = unknown
};

struct BuildOptions {
    std::uint64_t memoryBudgetBytes = 1ull << 30;
    /** Bytes per page; empty = auto: chosen after the scan so that whole-page padding stays a
     *  small share of the file without multiplying the draw commands of instances
     *  (builder/src/PageSizeChoice.h), at most kDefaultPageSize. */
    std::optional<std::uint32_t> pageSize;
    /** Worker threads for chunk building; 0 = hardware concurrency. */
    unsigned threads = 0;
    HierarchyParams hierarchy;
    /** Where spill files go; empty = beside the output file. */
    std::filesystem::path tempDirectory;
    /** How spill files store triangles and records (`farfield build --spill`): compact, the
     *  default, wrote 2.5x fewer bytes on the 200 M terrain for 6 % more time; raw costs no
     *  encoding time. */
    SpillCodec spillCodec = SpillCodec::Compact;
    /** storage::kFormatVersion2 (the default: compact clusters and 48-byte records) or
     *  kFormatVersion (`farfield build --format 1`, kept until version 1 is refused). The runtime
     *  draws both. */
    std::uint32_t formatVersion = storage::kFormatVersion2;
    /** Applied to every instance before anything else: moves and scales the whole input in the
     *  world (`farfield build --offset/--scale`). */
    glm::dmat4 placement{1.0};
    /** JSON object merged into the file's Metadata section (e.g. source, cameras). */
    std::string metadataJson = "{}";
    std::function<void(const BuildProgress&)> progress;
};

struct PhaseTime {
    std::string phase;
    double seconds = 0.0;
};

/** What a build did, for the JSON build report. */
struct BuildReport {
    std::uint64_t inputTriangles = 0;      ///< received by the sink
    std::uint64_t droppedNonFinite = 0;    ///< NaN/Inf positions
    std::uint64_t droppedDegenerate = 0;   ///< zero area
    std::uint32_t formatVersion = 0;
    std::uint64_t storedTriangles = 0;     ///< in the file (prototypes once; v2: kept by the codec)
    std::uint64_t clusters = 0;            ///< v2: clusters written
    std::uint64_t wideClusters = 0;        ///< v2: of them with 32-bit coordinates
    std::uint64_t clusterVertices = 0;     ///< v2: vertices over all clusters
    std::uint64_t clusterBytes = 0;        ///< v2: encoded clusters (the geometry pages less their slack)
    bool standIns = false;                 ///< v2: HierarchyParams's
    std::uint64_t standInNodes = 0;        ///< v2: cells that kept a stand-in (simplified or splats)
    std::uint64_t standInTriangles = 0;    ///< v2: their triangles, as the codec kept them (splat sets' too)
    std::uint64_t standInBytes = 0;        ///< v2: their encoded clusters (within clusterBytes)
    std::uint64_t standInsNotReducing = 0; ///< v2: cells whose simplification kept over 0.6 x
    std::uint64_t standInsTooSmall = 0;    ///< v2: cells under 256 triangles to simplify
    std::uint64_t standInsTooLarge = 0;    ///< v2: sources over 2^20, stand-ins over a page limit, or above what could not be
    int splatSpacing = 0;                  ///< v2: HierarchyParams's (0: no splats)
    bool standInsMeasured = false;         ///< v2: HierarchyParams::measureStandIns (with stand-ins or splats)
    std::uint64_t standInsNotPaying = 0;   ///< v2: cells whose candidates kept their shape only under 2 px (measured)
    std::uint64_t standInErrorsRaised = 0; ///< v2: kept stand-ins whose error the measure raised
    std::uint64_t splatsNotPaying = 0;     ///< v2: splat sets that kept their shape only under 2 px (measured)
    std::uint64_t splatsOverSimplified = 0; ///< v2: cells where both kinds paid and splats measured better
    std::uint64_t splatNodes = 0;          ///< v2: of standInNodes, those whose stand-in is splats
    std::uint64_t splats = 0;              ///< v2: their points (their triangles are in standInTriangles)
    std::uint64_t splatsNotReducing = 0;   ///< v2: splat sets over 0.6 x their source: not kept
    std::uint64_t splatsTooLarge = 0;      ///< v2: splat sets over 2^18 candidate bins or a page limit
    std::uint32_t maxGridBits = 0;         ///< v2: the largest prototype grid
    std::uint64_t instancedTriangles = 0;  ///< as drawn
    std::uint32_t prototypes = 0;
    std::uint32_t emptyPrototypes = 0;     ///< no triangle survived; their instances are dropped
    std::uint64_t instances = 0;
    std::uint64_t nodes = 0;
    std::uint64_t leafNodes = 0;           ///< prototype nodes without children (geometry nodes)
    std::string decomposition;             ///< HierarchyParams::decomposition's name
    /** Format 2: the largest and the smallest leaf a prototype got (HierarchyParams::leavesFor
     *  its placements and size; 0 for format 1 or without prototypes). */
    std::uint64_t clusterLeafTriangles = 0;
    std::uint64_t smallestClusterLeafTriangles = 0;
    /** Format 2: the prototypes whose leaves were split into cluster nodes (leavesFor). */
    std::uint32_t clusterNodePrototypes = 0;
    std::uint32_t maxDepth = 0;            ///< deepest prototype level
    std::uint32_t instanceLevelDepth = 0;
    std::uint64_t chunks = 0;
    std::uint64_t nodePages = 0;
    std::uint64_t geometryPages = 0;
    std::uint64_t tablePages = 0;
    std::uint64_t fileBytes = 0;
    std::uint64_t nodeBytes = 0;
    std::uint64_t geometryBytes = 0;
    std::uint64_t tableBytes = 0;
    std::uint64_t spillBytes = 0;          ///< written to temporary run files (encoded)
    std::string spillCodec;                ///< BuildOptions::spillCodec's name
    std::uint64_t memoryBudgetBytes = 0;
    std::uint64_t peakRssBytes = 0;        ///< VmHWM of the process at the end
    std::uint32_t pageSize = 0;            ///< as written (chosen, with auto)
    bool pageSizeAuto = false;
    unsigned threads = 0;
    std::array<double, 3> origin{}; ///< world position of the file frame's origin
    std::vector<PhaseTime> phases;
};

/** The report as a JSON object (stable keys, documented in README "build report"). */
std::string buildReportJson(const BuildReport& report);

/**
 * Builds one scene file. Feed it through the ISceneSink interface, then call finish().
 * Single-threaded API (it owns its worker threads internally).
 */
class SceneBuilder final : public ISceneSink {
public:
    /** Errors: InvalidArgument (page size, budget smaller than the minimum), IoError. */
    [[nodiscard]] static Result<std::unique_ptr<SceneBuilder>> create(
            const std::filesystem::path& outputPath, const BuildOptions& options);

    ~SceneBuilder() override;
    SceneBuilder(const SceneBuilder&) = delete;
    SceneBuilder& operator=(const SceneBuilder&) = delete;

    [[nodiscard]] Result<PrototypeId> addPrototype(std::string_view name) override;
    [[nodiscard]] Status addTriangles(
            PrototypeId prototype, std::span<const storage::PackedTriangle> triangles) override;
    [[nodiscard]] Status addInstance(PrototypeId prototype, const glm::dmat4& transform) override;
    /** Kept for ORSD (HierarchyParams::decomposition); errors: InvalidArgument for an unknown
     *  prototype or a grid that is empty or not finite. */
    [[nodiscard]] Status declareVoxelGrid(PrototypeId prototype, const VoxelGrid& grid) override;

    /** Replaces BuildOptions::metadataJson (sources learn their cameras only while feeding). */
    void setMetadataJson(std::string json);

    /** Runs partition, hierarchy and write; the file exists under its final name only if this
     *  succeeds. Temporary files are removed either way. */
    [[nodiscard]] Result<BuildReport> finish();

    /** The smallest budget the builder accepts. */
    static constexpr std::uint64_t kMinimumBudgetBytes = 16ull << 20;

private:
    struct Impl;
    explicit SceneBuilder(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> mImpl;
};

} // namespace ff::builder
