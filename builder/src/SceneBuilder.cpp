#include <ff/builder/SceneBuilder.h>

#include "FileFrame.h"
#include "InstanceLevel.h"
#include "PageSizeChoice.h"
#include "PrototypeBuilder.h"
#include "RunFile.h"

#include <ff/builder/GridChoice.h>
#include <ff/storage/ProcessMemory.h>
#include <ff/storage/PrototypeRecordV2.h>
#include <ff/storage/SceneWriter.h>

#include <glm/gtc/matrix_transform.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <thread>
#include <stdlib.h> // mkdtemp
#include <unistd.h>

namespace ff::builder {

namespace {

using Clock = std::chrono::steady_clock;

bool isFinite(const storage::PackedTriangle& t) {
    for (const storage::PackedVertex& v : t.vertices)
        for (float c : v.position)
            if (!std::isfinite(c))
                return false;
    return true;
}

bool hasArea(const storage::PackedTriangle& t) {
    const glm::dvec3 a(t.vertices[0].position[0], t.vertices[0].position[1], t.vertices[0].position[2]);
    const glm::dvec3 b(t.vertices[1].position[0], t.vertices[1].position[1], t.vertices[1].position[2]);
    const glm::dvec3 c(t.vertices[2].position[0], t.vertices[2].position[1], t.vertices[2].position[2]);
    const glm::dvec3 n = glm::cross(b - a, c - a);
    return glm::dot(n, n) > 0.0;
}

struct PrototypeState {
    std::string name;
    RunFile run;
    glm::vec3 boundsMin{std::numeric_limits<float>::infinity()};
    glm::vec3 boundsMax{-std::numeric_limits<float>::infinity()};
    std::optional<VoxelGrid> grid;
    EdgeSampler edges; ///< v2: what its position grid's step is chosen from
};

} // namespace

struct SceneBuilder::Impl {
    std::filesystem::path outputPath;
    BuildOptions options;
    std::filesystem::path tempDirectory;
    std::unique_ptr<storage::SceneWriter> writer;
    std::vector<std::unique_ptr<PrototypeState>> prototypes;
    std::vector<std::pair<PrototypeId, glm::dmat4>> instances; ///< world transforms
    BuildReport report;
    std::size_t spillBufferLimit = 0; ///< total bytes all run files may buffer
    std::size_t spillBuffered = 0;
    Clock::time_point scanStart = Clock::now();
    bool finished = false;

    Impl() = default;
    Impl(const Impl&) = delete;
    Impl& operator=(const Impl&) = delete;
    /** Whatever happened (finish() failed or was never called), no temporary file survives. */
    ~Impl() { removeTemporaryFiles(); }

    void removeTemporaryFiles() noexcept {
        prototypes.clear(); // run files unlink themselves
        writer.reset();     // an uncommitted writer removes its temporary output
        if (!tempDirectory.empty()) {
            std::error_code ec;
            std::filesystem::remove_all(tempDirectory, ec);
            tempDirectory.clear();
        }
    }

    Status spill(PrototypeState& proto, std::span<const storage::PackedTriangle> triangles);
    /** `--page-size auto`: picks the page size from what the scan saw and reopens the writer
     *  with it (it has written nothing yet). */
    Status choosePageSize();
    void progress(const char* phase, std::uint64_t done, std::uint64_t total) const {
        if (options.progress)
            options.progress({phase, done, total});
    }
};

SceneBuilder::SceneBuilder(std::unique_ptr<Impl> impl) : mImpl(std::move(impl)) {}
SceneBuilder::~SceneBuilder() = default;

Result<std::unique_ptr<SceneBuilder>> SceneBuilder::create(
        const std::filesystem::path& outputPath, const BuildOptions& options) {
    if (options.memoryBudgetBytes < kMinimumBudgetBytes)
        return Status(
                ErrorCode::InvalidArgument,
                "--memory-budget " + std::to_string(options.memoryBudgetBytes >> 20) + " MiB is below the minimum of " +
                        std::to_string(kMinimumBudgetBytes >> 20) + " MiB");
    if (options.pageSize && !storage::isValidPageSize(*options.pageSize))
        return Status(ErrorCode::InvalidArgument, "page size must be a power of two between 4 KiB and 16 MiB");
    if (options.hierarchy.bakeResolution < 2 || options.hierarchy.bakeResolution > 64)
        return Status(ErrorCode::InvalidArgument, "bake resolution must be between 2 and 64");
    if (!(options.hierarchy.cubeCost > 0.0f) || !(options.hierarchy.largeTriangleTolerance > 0.0f))
        return Status(ErrorCode::InvalidArgument, "cube cost and large-triangle tolerance must be positive");
    if (options.formatVersion != storage::kFormatVersion && options.formatVersion != storage::kFormatVersion2)
        return Status(ErrorCode::InvalidArgument, "format version must be 1 or 2");
    if (options.hierarchy.anyStandIns() && options.formatVersion != storage::kFormatVersion2)
        return Status(ErrorCode::InvalidArgument, "stand-ins and splats need format 2 (--format 2)");
    if (options.hierarchy.splatSpacing < 0 || options.hierarchy.splatSpacing > 64)
        return Status(ErrorCode::InvalidArgument, "splat spacing must be a cell's 1/1 to 1/64 (8-16 are usual)");

    auto impl = std::make_unique<Impl>();
    impl->outputPath = outputPath;
    impl->options = options;
    if (impl->options.threads == 0)
        impl->options.threads = std::max(1u, std::thread::hardware_concurrency());
    std::filesystem::path parent = outputPath.parent_path();
    if (parent.empty())
        parent = ".";
    const std::filesystem::path tempRoot = options.tempDirectory.empty() ? parent : options.tempDirectory;
    std::error_code ec;
    std::filesystem::create_directories(tempRoot, ec);
    if (ec)
        return Status(ErrorCode::IoError, "cannot create directory " + tempRoot.string() + ": " + ec.message());
    // A fresh directory per builder: builders sharing an output directory, in one process or
    // several, must not share run files. From here on ~Impl removes it on every path.
    std::string pattern = (tempRoot / ".farfield-build-XXXXXX").string();
    if (::mkdtemp(pattern.data()) == nullptr)
        return ioStatus(errno, "cannot create temporary directory in", tempRoot);
    impl->tempDirectory = pattern;
    // Opened now so an unwritable output fails before the scan; with auto, finish() reopens
    // it once the page size is chosen (nothing is written before that).
    storage::SceneWriterOptions writerOptions;
    writerOptions.pageSize = options.pageSize.value_or(storage::kDefaultPageSize);
    writerOptions.formatVersion = options.formatVersion;
    FF_ASSIGN_OR_RETURN(impl->writer, storage::SceneWriter::create(outputPath, writerOptions));
    impl->report.formatVersion = options.formatVersion;
    impl->spillBufferLimit = static_cast<std::size_t>(options.memoryBudgetBytes / 8);
    impl->report.memoryBudgetBytes = options.memoryBudgetBytes;
    impl->report.pageSize = writerOptions.pageSize;
    impl->report.pageSizeAuto = !options.pageSize.has_value();
    impl->report.threads = impl->options.threads;
    impl->report.decomposition = std::string(decompositionName(options.hierarchy.decomposition));
    if (options.formatVersion == storage::kFormatVersion2) {
        impl->report.standIns = options.hierarchy.standIns;
        impl->report.splatSpacing = options.hierarchy.splatSpacing;
        impl->report.standInsMeasured = options.hierarchy.anyStandIns() && options.hierarchy.measureStandIns;
    }
    impl->report.spillCodec = std::string(spillCodecName(options.spillCodec));
    return std::unique_ptr<SceneBuilder>(new SceneBuilder(std::move(impl)));
}

Result<PrototypeId> SceneBuilder::addPrototype(std::string_view name) {
    const auto id = static_cast<PrototypeId>(mImpl->prototypes.size());
    auto state = std::make_unique<PrototypeState>(PrototypeState{
            std::string(name), RunFile(mImpl->tempDirectory / ("proto" + std::to_string(id) + ".run"), mImpl->options.spillCodec), {}, {},
            std::nullopt, {}});
    state->boundsMin = glm::vec3(std::numeric_limits<float>::infinity());
    state->boundsMax = glm::vec3(-std::numeric_limits<float>::infinity());
    mImpl->prototypes.push_back(std::move(state));
    return id;
}

Status SceneBuilder::addTriangles(PrototypeId prototype, std::span<const storage::PackedTriangle> triangles) {
    if (prototype >= mImpl->prototypes.size())
        return Status(ErrorCode::InvalidArgument, "unknown prototype " + std::to_string(prototype));
    return mImpl->spill(*mImpl->prototypes[prototype], triangles);
}

Status SceneBuilder::Impl::spill(PrototypeState& proto, std::span<const storage::PackedTriangle> triangles) {
    report.inputTriangles += triangles.size();
    // Keep runs of valid triangles together so the common case appends whole batches.
    std::size_t runBegin = 0;
    auto flushRun = [&](std::size_t runEnd) -> Status {
        if (runEnd > runBegin) {
            const auto run = triangles.subspan(runBegin, runEnd - runBegin);
            for (const storage::PackedTriangle& t : run)
                for (const storage::PackedVertex& v : t.vertices) {
                    proto.boundsMin = glm::min(proto.boundsMin, glm::vec3(v.position[0], v.position[1], v.position[2]));
                    proto.boundsMax = glm::max(proto.boundsMax, glm::vec3(v.position[0], v.position[1], v.position[2]));
                }
            FF_RETURN_IF_ERROR(proto.run.append(run));
            if (options.formatVersion == storage::kFormatVersion2)
                proto.edges.add(run);
            spillBuffered += run.size_bytes(); // an over-estimate once a run flushes itself
        }
        return Status::ok();
    };
    for (std::size_t i = 0; i < triangles.size(); ++i) {
        const storage::PackedTriangle& t = triangles[i];
        const bool finite = isFinite(t);
        if (finite && hasArea(t))
            continue;
        FF_RETURN_IF_ERROR(flushRun(i));
        runBegin = i + 1;
        if (!finite)
            ++report.droppedNonFinite;
        else
            ++report.droppedDegenerate;
    }
    FF_RETURN_IF_ERROR(flushRun(triangles.size()));
    if (spillBuffered > spillBufferLimit) {
        for (auto& p : prototypes)
            FF_RETURN_IF_ERROR(p->run.flush());
        spillBuffered = 0;
    }
    return Status::ok();
}

Status SceneBuilder::addInstance(PrototypeId prototype, const glm::dmat4& transform) {
    if (prototype >= mImpl->prototypes.size())
        return Status(ErrorCode::InvalidArgument, "unknown prototype " + std::to_string(prototype));
    const glm::dmat4 world = mImpl->options.placement * transform;
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r)
            if (!std::isfinite(transform[c][r]) || !std::isfinite(world[c][r]))
                return Status(ErrorCode::InvalidInput, "instance of prototype " + std::to_string(prototype) + ": transform is not finite");
    mImpl->instances.emplace_back(prototype, world);
    return Status::ok();
}

Status SceneBuilder::declareVoxelGrid(PrototypeId prototype, const VoxelGrid& grid) {
    if (prototype >= mImpl->prototypes.size())
        return Status(ErrorCode::InvalidArgument, "unknown prototype " + std::to_string(prototype));
    const bool finite = std::isfinite(grid.origin.x) && std::isfinite(grid.origin.y) && std::isfinite(grid.origin.z);
    if (!finite || !(grid.cellSize > 0.0f) || !std::isfinite(grid.cellSize) || grid.cells.x == 0 || grid.cells.y == 0 ||
        grid.cells.z == 0 || std::max({grid.cells.x, grid.cells.y, grid.cells.z}) > (1u << 20))
        return Status(ErrorCode::InvalidArgument,
                      "prototype " + std::to_string(prototype) +
                              ": a voxel grid needs a finite origin, a positive cell size and 1 to 2^20 cells an axis");
    mImpl->prototypes[prototype]->grid = grid;
    return Status::ok();
}

void SceneBuilder::setMetadataJson(std::string json) { mImpl->options.metadataJson = std::move(json); }

Result<BuildReport> SceneBuilder::finish() {
    Impl& s = *mImpl;
    if (s.finished)
        return Status(ErrorCode::InvalidArgument, "finish() called twice");
    s.finished = true;
    BuildReport& report = s.report;
    auto phaseEnd = [&report](const char* name, Clock::time_point start) {
        report.phases.push_back({name, std::chrono::duration<double>(Clock::now() - start).count()});
        return Clock::now();
    };
    Clock::time_point start = phaseEnd("scan", s.scanStart);
    // "Temporary files are removed either way", as soon as finish() returns.
    struct CleanupGuard {
        Impl& impl;
        ~CleanupGuard() { impl.removeTemporaryFiles(); }
    } guard{s};

    if (report.pageSizeAuto)
        FF_RETURN_IF_ERROR(s.choosePageSize());

    // ---- partition + buildHierarchy, one prototype at a time ---------------------------------
    const std::uint64_t fixedReserve = std::min<std::uint64_t>(s.options.memoryBudgetBytes / 4, 64ull << 20);
    const std::uint64_t chunkBudget = (s.options.memoryBudgetBytes - fixedReserve) / s.options.threads;
    const std::uint64_t bytesPerTriangle = kChunkBytesPerTriangle +
            (s.options.hierarchy.decomposition == Decomposition::Octree ? 0 : kDecompositionBytesPerTriangle);
    const std::uint64_t chunkTriangles = chunkBudget / bytesPerTriangle;
    // Out of the fixed reserve: a chunked prototype gathers each octree level's triangles in an
    // extent of this size, budget/256 up to 1 MiB, before writing them (at most maxDepth + 1
    // levels: 21 MiB at 1 GiB).
    const std::uint64_t levelExtentBytes = std::min<std::uint64_t>(fixedReserve / 64, 1u << 20);
    const bool v2 = s.options.formatVersion == storage::kFormatVersion2;
    NodePageTable nodePageTable(s.writer->pageSize()); // v2: every Nodes page, in node-index order
    PrototypeBuilder protoBuilder(
            *s.writer, s.options.hierarchy, chunkTriangles, levelExtentBytes, s.options.threads, s.tempDirectory,
            s.options.spillCodec, s.options.progress, v2 ? &nodePageTable : nullptr);
    // Prototypes left without triangles get no record (a record needs a root node): the table
    // holds the others in declaration order, and storedIndex maps declared ids to it.
    constexpr std::uint32_t kNotStored = std::numeric_limits<std::uint32_t>::max();
    std::vector<std::uint32_t> storedIndex(s.prototypes.size(), kNotStored);
    std::vector<storage::PrototypeRecord> protoRecords;
    std::vector<storage::PrototypeV2> protoRecordsV2; // v2: what the Prototypes section holds
    std::vector<PrototypeSummary> summaries;
    nlohmann::json names = nlohmann::json::array(); // per stored prototype
    std::vector<std::uint64_t> placements(s.prototypes.size(), 0); // each prototype's instances
    for (const auto& instance : s.instances)
        ++placements[instance.first];
    for (std::size_t p = 0; p < s.prototypes.size(); ++p) {
        s.progress("hierarchy", p, s.prototypes.size());
        PrototypeState& proto = *s.prototypes[p];
        if (proto.run.count() == 0) {
            ++report.emptyPrototypes;
            continue;
        }
        // Building reads the run file back from disk: all of it counts as spilled.
        FF_RETURN_IF_ERROR(proto.run.flush());
        report.spillBytes += proto.run.bytesWritten();
        std::optional<PrototypeEncodingV2> encoding;
        if (v2) {
            FF_ASSIGN_OR_RETURN(
                    const storage::PositionGrid positionGrid,
                    chooseGrid({proto.boundsMin.x, proto.boundsMin.y, proto.boundsMin.z},
                               {proto.boundsMax.x, proto.boundsMax.y, proto.boundsMax.z},
                               proto.edges));
            encoding = PrototypeEncodingV2{
                    positionGrid,
                    static_cast<std::uint32_t>(protoRecords.size()),
                    s.options.hierarchy.leavesFor(placements[p], proto.run.count())};
            const std::uint64_t leaf = encoding->leaves.leafTriangles;
            report.clusterLeafTriangles = std::max(report.clusterLeafTriangles, leaf);
            report.smallestClusterLeafTriangles =
                    report.smallestClusterLeafTriangles == 0 ? leaf : std::min(report.smallestClusterLeafTriangles, leaf);
            if (encoding->leaves.clusterNodes)
                ++report.clusterNodePrototypes;
            report.maxGridBits = std::max<std::uint32_t>(report.maxGridBits, static_cast<std::uint32_t>(positionGrid.bits));
        }
        FF_ASSIGN_OR_RETURN(
                PrototypeBuildResult built,
                protoBuilder.build(
                        static_cast<std::uint32_t>(p), proto.run, proto.boundsMin, proto.boundsMax,
                        proto.grid ? &*proto.grid : nullptr, encoding ? &*encoding : nullptr, report.spillBytes));
        storedIndex[p] = static_cast<std::uint32_t>(protoRecords.size());
        protoRecords.push_back(built.record);
        if (v2)
            protoRecordsV2.push_back(built.recordV2);
        report.clusters += built.clusters.clusters;
        report.wideClusters += built.clusters.wideClusters;
        report.clusterVertices += built.clusters.clusterVertices;
        report.clusterBytes += built.clusters.encodedBytes + built.standInClusters.encodedBytes;
        report.clusters += built.standInClusters.clusters;
        report.wideClusters += built.standInClusters.wideClusters;
        report.clusterVertices += built.standInClusters.clusterVertices;
        report.standInNodes += built.standIns;
        report.standInTriangles += built.standInClusters.trianglesKept;
        report.standInBytes += built.standInClusters.encodedBytes;
        report.standInsNotReducing += built.standInCounts.notReducing;
        report.standInsTooSmall += built.standInCounts.tooSmall;
        report.standInsTooLarge += built.standInCounts.tooLarge;
        report.splatNodes += built.standInCounts.splats;
        report.splats += built.standInClusters.points;
        report.splatsNotReducing += built.standInCounts.splatsNotReducing;
        report.splatsTooLarge += built.standInCounts.splatsTooLarge;
        report.standInsNotPaying += built.standInCounts.notPaying;
        report.standInErrorsRaised += built.standInCounts.errorsRaised;
        report.splatsNotPaying += built.standInCounts.splatsNotPaying;
        report.splatsOverSimplified += built.standInCounts.splatsOverSimplified;
        summaries.push_back(std::move(built.summary));
        names.push_back(proto.name);
        report.storedTriangles += built.record.triangleCount;
        report.nodes += built.nodes;
        report.leafNodes += built.leafNodes;
        report.maxDepth = std::max(report.maxDepth, built.maxDepth);
        report.chunks += built.chunks;
        report.geometryPages += built.geometryPages;
        report.nodePages += built.nodePages;
    }
    report.prototypes = static_cast<std::uint32_t>(s.prototypes.size());
    s.progress("hierarchy", s.prototypes.size(), s.prototypes.size());
    start = phaseEnd("hierarchy", start);

    // ---- instance level -----------------------------------------------------------------------
    // Transforms become float only now, relative to the file frame's origin, so a scene far
    // from the world origin keeps its precision (storage/FORMAT.md "The file frame").
    WorldBounds world;
    for (const auto& [prototype, transform] : s.instances)
        if (storedIndex[prototype] != kNotStored)
            world.add(transform, protoRecords[storedIndex[prototype]]);
    const glm::dvec3 origin = chooseFileOrigin(world);
    report.origin = {origin.x, origin.y, origin.z};
    const glm::dmat4 toFileFrame = glm::translate(glm::dmat4(1.0), -origin);
    std::vector<storage::InstanceRecord> instanceRecords;
    instanceRecords.reserve(s.instances.size());
    for (const auto& [prototype, transform] : s.instances) {
        const std::uint32_t stored = storedIndex[prototype];
        if (stored == kNotStored)
            continue;
        storage::InstanceRecord record{};
        record.transform = toRowMajor3x4(glm::mat4(toFileFrame * transform));
        record.prototype = stored;
        instanceRecords.push_back(record);
        report.instancedTriangles += protoRecords[stored].triangleCount;
    }
    report.instances = instanceRecords.size();
    s.progress("instances", 0, 1);
    FF_ASSIGN_OR_RETURN(
            InstanceLevelResult level,
            buildInstanceLevel(
                    *s.writer, instanceRecords, protoRecords, summaries, s.options.hierarchy, v2 ? &nodePageTable : nullptr));
    report.nodes += level.nodes;
    report.nodePages += level.nodePages;
    if (v2) { // the last node page; the report counts the pages written
        FF_RETURN_IF_ERROR(nodePageTable.writeOpen(*s.writer));
        report.nodePages = nodePageTable.pages().size();
    }
    report.instanceLevelDepth = level.depth;
    start = phaseEnd("instances", start);

    // ---- write: tables, metadata, header -----------------------------------------------------
    s.progress("write", 0, 1);
    std::vector<storage::SectionEntry> sections;
    const std::uint64_t tableStart = s.writer->nextPageIndex();
    std::vector<std::byte> protoBytes;
    if (v2) {
        protoBytes.resize(protoRecordsV2.size() * storage::kPrototypeRecordV2Size);
        for (std::size_t i = 0; i < protoRecordsV2.size(); ++i)
            FF_RETURN_IF_ERROR(storage::encodePrototypeV2(
                    protoRecordsV2[i],
                    std::span(protoBytes).subspan(i * storage::kPrototypeRecordV2Size, storage::kPrototypeRecordV2Size)));
    } else {
        const auto bytes = std::as_bytes(std::span(protoRecords));
        protoBytes.assign(bytes.begin(), bytes.end());
    }
    nlohmann::json metadata = nlohmann::json::parse(s.options.metadataJson, nullptr, false);
    if (!metadata.is_object())
        metadata = nlohmann::json::object();
    metadata["prototypeNames"] = names;
    // The same input must give the same bytes (DESIGN.md "deterministic output"), whatever the
    // machine and --threads: the report stored in the file leaves out timings, memory use and
    // the thread count (by default the machine's cores); the returned report has them.
    nlohmann::json build = nlohmann::json::parse(buildReportJson(report));
    for (const char* machineDependent : {"seconds", "total_seconds", "peak_rss_bytes", "threads"})
        build.erase(machineDependent);
    metadata["build"] = std::move(build);
    const std::string metadataText = metadata.dump();
    std::vector<storage::SceneWriter::SectionStream> streams = {
            {storage::SectionType::Prototypes, protoBytes, protoRecords.size()},
            {storage::SectionType::Instances, std::as_bytes(std::span(instanceRecords)), instanceRecords.size()},
            {storage::SectionType::Metadata, std::as_bytes(std::span(metadataText)), 1},
    };
    if (v2)
        streams.push_back({storage::SectionType::NodePages, std::as_bytes(std::span(nodePageTable.pages())), nodePageTable.pages().size()});
    FF_ASSIGN_OR_RETURN(sections, s.writer->appendSections(streams));
    storage::SectionEntry hierarchy{};
    hierarchy.type = static_cast<std::uint32_t>(storage::SectionType::Hierarchy);
    hierarchy.firstPage = 1;
    hierarchy.pageCount = tableStart - 1;
    sections.push_back(hierarchy);
    report.tablePages = s.writer->nextPageIndex() - tableStart;

    storage::FileHeader header{};
    header.root = level.root;
    if (v2) {
        header.root = {level.rootNode, 0};
        header.flags = storage::kFileV2HasRoot;
    }
    header.boundsMin = {level.boundsMin.x, level.boundsMin.y, level.boundsMin.z};
    header.boundsMax = {level.boundsMax.x, level.boundsMax.y, level.boundsMax.z};
    header.nodeCount = report.nodes;
    header.storedTriangles = report.storedTriangles;
    header.instancedTriangles = report.instancedTriangles;
    header.origin = report.origin;
    const std::uint64_t pageCount = s.writer->nextPageIndex();
    FF_RETURN_IF_ERROR(s.writer->commit(header, sections));
    phaseEnd("write", start);
    s.progress("write", 1, 1);

    const std::uint64_t page = report.pageSize;
    report.fileBytes = pageCount * page;
    report.nodeBytes = report.nodePages * page;
    report.geometryBytes = report.geometryPages * page;
    report.tableBytes = report.tablePages * page;
    report.peakRssBytes = storage::readProcessMemory().peakRssBytes;
    return report;
}

Status SceneBuilder::Impl::choosePageSize() {
    PageSizeInputs inputs;
    inputs.formatVersion = options.formatVersion;
    inputs.prototypes.resize(prototypes.size());
    for (std::size_t p = 0; p < prototypes.size(); ++p)
        inputs.prototypes[p].triangles = prototypes[p]->run.count();
    for (const auto& [prototype, transform] : instances)
        ++inputs.prototypes[prototype].instances;
    const std::uint32_t chosen = builder::choosePageSize(inputs);
    if (chosen == writer->pageSize())
        return Status::ok();
    writer.reset();
    storage::SceneWriterOptions writerOptions;
    writerOptions.pageSize = chosen;
    writerOptions.formatVersion = options.formatVersion;
    FF_ASSIGN_OR_RETURN(writer, storage::SceneWriter::create(outputPath, writerOptions));
    report.pageSize = chosen;
    return Status::ok();
}

std::string buildReportJson(const BuildReport& r) {
    nlohmann::json phases = nlohmann::json::object();
    double total = 0.0;
    for (const PhaseTime& p : r.phases) {
        phases[p.phase] = p.seconds;
        total += p.seconds;
    }
    nlohmann::json j = {
            {"input_triangles", r.inputTriangles},
            {"dropped_non_finite_triangles", r.droppedNonFinite},
            {"dropped_degenerate_triangles", r.droppedDegenerate},
            {"format_version", r.formatVersion},
            {"stored_triangles", r.storedTriangles},
            {"instanced_triangles", r.instancedTriangles},
            {"prototypes", r.prototypes},
            {"empty_prototypes", r.emptyPrototypes},
            {"instances", r.instances},
            {"decomposition", r.decomposition},
            {"cluster_leaf_triangles", r.clusterLeafTriangles},
            {"smallest_cluster_leaf_triangles", r.smallestClusterLeafTriangles},
            {"cluster_nodes", r.clusterNodePrototypes > 0},
            {"cluster_node_prototypes", r.clusterNodePrototypes},
            {"stand_ins",
             {{"enabled", r.standIns},
              {"nodes", r.standInNodes},
              {"triangles", r.standInTriangles},
              {"bytes", r.standInBytes},
              {"not_reducing", r.standInsNotReducing},
              {"too_small", r.standInsTooSmall},
              {"too_large", r.standInsTooLarge},
              {"choice", r.standInsMeasured ? "measured" : "rule"},
              {"not_paying", r.standInsNotPaying},
              {"errors_raised", r.standInErrorsRaised}}},
            {"splats",
             {{"spacing", r.splatSpacing},
              {"nodes", r.splatNodes},
              {"points", r.splats},
              {"not_reducing", r.splatsNotReducing},
              {"too_large", r.splatsTooLarge},
              {"not_paying", r.splatsNotPaying},
              {"chosen_over_simplified", r.splatsOverSimplified}}},
            {"nodes", r.nodes},
            {"leaf_nodes", r.leafNodes},
            {"depth", r.maxDepth},
            {"instance_level_depth", r.instanceLevelDepth},
            {"chunks", r.chunks},
            {"page_size", r.pageSize},
            {"page_size_auto", r.pageSizeAuto},
            {"origin", r.origin},
            {"threads", r.threads},
            {"bytes",
             {{"file", r.fileBytes},
              {"nodes", r.nodeBytes},
              {"geometry", r.geometryBytes},
              {"tables", r.tableBytes},
              {"spill", r.spillBytes}}},
            {"pages", {{"nodes", r.nodePages}, {"geometry", r.geometryPages}, {"tables", r.tablePages}}},
            {"spill_codec", r.spillCodec},
            {"clusters", {{"count", r.clusters}, {"wide", r.wideClusters}, {"vertices", r.clusterVertices}, {"bytes", r.clusterBytes}, {"max_grid_bits", r.maxGridBits}}},
            {"seconds", phases},
            {"total_seconds", total},
            {"memory_budget_bytes", r.memoryBudgetBytes},
            {"peak_rss_bytes", r.peakRssBytes},
    };
    return j.dump(2);
}

} // namespace ff::builder
