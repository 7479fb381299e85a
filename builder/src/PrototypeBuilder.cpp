#include "PrototypeBuilder.h"

#include "ClusterNodes.h"
#include "Decomposition.h"
#include "HierarchyBuild.h"
#include "LevelRegions.h"
#include "LevelRegionsV2.h"
#include "Morton.h"
#include "SubtreeEncoder.h"

#include <ff/storage/Assert.h>
#include <ff/storage/NodeCellV2.h>

#include <algorithm>
#include <cmath>
#include <future>
#include <limits>
#include <string>
#include <unordered_map>

namespace ff::builder {

namespace {

StandInKinds standInKinds(const HierarchyParams& params) {
    return {params.standIns, params.splatSpacing, params.measureStandIns};
}

LeafShapeV2 leafShapeV2(const HierarchyParams& params, const PrototypeEncodingV2& encoding, unsigned threads) {
    LeafShapeV2 shape;
    shape.leafTriangles = encoding.leaves.leafTriangles;
    shape.clusterNodes = encoding.leaves.clusterNodes;
    shape.grid = &encoding.grid;
    shape.bakeResolution = params.bakeResolution;
    shape.threads = threads;
    return shape;
}

struct ChunkOutput {
    LevelledSubtree encoded;
    std::optional<ChunkClustersV2> clusters; ///< format 2: its clusters, its triangles freed
    PrototypeSummary summary;
    std::uint64_t leafNodes = 0;
    StandInCounts standInCounts;
};

/** A cell above the chunks of a partitioned prototype. */
struct TopNode {
    Cell cell;
    int level = 0;
    int octant = 0;
    std::uint64_t key = 0; ///< Morton prefix of the cell at `level`
    std::uint32_t firstChild = 0;
    std::uint32_t childCount = 0;
    std::int64_t chunk = -1; ///< index into the chunk list if this cell is a chunk
    std::vector<storage::PackedTriangle> own; ///< large triangles that stop here
};

constexpr int kMaxCountLevel = 16;

/** Morton key of the level-`level` cell containing `p` (bit order per level: x, y, z). */
std::uint64_t cellKey(const Cell& root, const glm::vec3& p, int level) {
    const double cells = std::ldexp(1.0, level);
    std::array<std::uint64_t, 3> index{};
    for (int a = 0; a < 3; ++a) {
        const double t = (static_cast<double>(p[a]) - root.min[a]) / root.size * cells;
        index[static_cast<std::size_t>(a)] = static_cast<std::uint64_t>(std::clamp(t, 0.0, cells - 1.0));
    }
    return spreadBits(index[0]) | (spreadBits(index[1]) << 1) | (spreadBits(index[2]) << 2);
}

void addToSummary(const BuildNode& node, PrototypeSummary& summary) {
    if (node.level > PrototypeSummary::kDepth)
        return;
    const bool leaf = node.childCount == 0;
    const int last = leaf ? PrototypeSummary::kDepth : node.level;
    for (int l = node.level; l <= last; ++l)
        summary.cuts[static_cast<std::size_t>(l)].push_back({node.cellMin, node.cellMax, node.cube});
}

/** A hierarchy as built, before its layout: what the tree above it and the report need. */
// Builds one hierarchy completely in memory. Runs on worker threads: touches only its arguments.
BuiltHierarchy buildInMemoryHierarchy(
        std::vector<storage::PackedTriangle>& triangles,
        const Cell& cell,
        int level,
        int octant,
        const HierarchyParams& params,
        const VoxelGrid* grid) {
    CubeBaker baker(params.bakeResolution);
    BuiltHierarchy out;
    out.nodes = buildHierarchy(triangles, cell, level, octant, params, baker, grid);
    for (const BuildNode& node : out.nodes) {
        addToSummary(node, out.summary);
        out.leafNodes += node.childCount == 0 ? 1u : 0u;
    }
    return out;
}

// Builds one chunk and lays it out level by level; format 2 (`encoding` set) makes its small
// subtrees leaves first and encodes its clusters. Runs on worker threads.
Result<ChunkOutput> buildChunk(
        std::vector<storage::PackedTriangle> triangles,
        const Cell& cell,
        int level,
        int octant,
        const HierarchyParams& params,
        const VoxelGrid* grid,
        const std::optional<PrototypeEncodingV2>& encoding,
        std::uint32_t pageSize) {
    BuiltHierarchy built = buildInMemoryHierarchy(triangles, cell, level, octant, params, grid);
    ChunkOutput out;
    out.summary = std::move(built.summary);
    out.leafNodes = built.leafNodes;
    const storage::PositionGrid* positionGrid = encoding ? &encoding->grid : nullptr;
    if (encoding)
        FF_RETURN_IF_ERROR(shapeLeavesV2(built.nodes, triangles, leafShapeV2(params, *encoding, 1)));
    std::vector<std::optional<StandIn>> standIns;
    StandInSource rootSource = StandInSource::unusable();
    if (positionGrid != nullptr && params.anyStandIns()) {
        FF_ASSIGN_OR_RETURN(
                standIns,
                buildStandIns(
                        built.nodes,
                        triangles,
                        *positionGrid,
                        {},
                        1,
                        &rootSource,
                        out.standInCounts,
                        {maxStandInTriangles(pageSize), false},
                        standInKinds(params)));
        if (rootSource.triangles.size() > kMaxCarriedStandInSource)
            rootSource = StandInSource::unusable();
    }
    out.encoded = encodeLevels(std::move(built.nodes), std::move(triangles), std::move(standIns));
    out.encoded.rootSource = std::move(rootSource);
    if (positionGrid != nullptr) {
        FF_ASSIGN_OR_RETURN(ChunkClustersV2 clusters, encodeChunkClusters(out.encoded, *positionGrid));
        out.clusters = std::move(clusters);
    }
    return out;
}

int chooseCountLevel(std::uint64_t triangles, std::uint64_t chunkTriangles) {
    const double ratio = static_cast<double>(triangles) / static_cast<double>(std::max<std::uint64_t>(chunkTriangles, 1));
    const int level = static_cast<int>(std::ceil(std::log(std::max(ratio, 1.0)) / std::log(8.0))) + 2;
    return std::clamp(level, 1, kMaxCountLevel);
}

} // namespace

PrototypeBuilder::PrototypeBuilder(
        storage::SceneWriter& writer,
        const HierarchyParams& params,
        std::uint64_t chunkTriangles,
        std::uint64_t levelExtentBytes,
        unsigned threads,
        std::filesystem::path tempDirectory,
        SpillCodec spillCodec,
        std::function<void(const BuildProgress&)> progress,
        NodePageTable* nodePageTable)
    : mWriter(writer)
    , mParams(params)
    // Below 2^32: the encoder orders a chunk's triangles through 32-bit indices (encodeLevels).
    , mChunkTriangles(std::clamp<std::uint64_t>(chunkTriangles, 1024, 0xFFFFFFFEull))
    , mLevelExtentBytes(levelExtentBytes)
    , mThreads(std::max(threads, 1u))
    , mTempDirectory(std::move(tempDirectory))
    , mSpillCodec(spillCodec)
    , mProgress(std::move(progress))
    , mNodePageTable(nodePageTable) {}

Result<PrototypeBuildResult> PrototypeBuilder::build(
        std::uint32_t prototypeId,
        RunFile& triangles,
        const glm::vec3& boundsMin,
        const glm::vec3& boundsMax,
        const VoxelGrid* grid,
        const PrototypeEncodingV2* encoding,
        std::uint64_t& spillBytes) {
    const bool v2 = mWriter.formatVersion() == storage::kFormatVersion2;
    if (v2 && (encoding == nullptr || mNodePageTable == nullptr))
        return Status(ErrorCode::Internal, "a format 2 build without a position grid or node page table");
    // The root cell is a cube around the bounds, a hair larger so no centroid sits on its max
    // face; a format 2 reader derives the same cube from the bounds (NodeCellV2.h).
    const glm::vec3 size = boundsMax - boundsMin;
    float padded = storage::rootCellEdge({size.x, size.y, size.z});
    Cell root{boundsMin, padded};
    if (mParams.decomposition == Decomposition::Orsd) {
        // ORSD's blocks are the grid's: the root is its smallest power-of-two block, so that the
        // octree cells above the chunks are blocks too.
        if (!grid)
            return Status(ErrorCode::InvalidArgument,
                          "prototype " + std::to_string(prototypeId) +
                                  ": --decomposition orsd needs a voxel grid, which only the isosurface generator "
                                  "declares; use octree, dbvd, phbvo or balanced for other inputs");
        const GridBlock block = rootGridBlock(*grid);
        padded = static_cast<float>(block.size) * grid->cellSize;
        root = Cell{grid->origin, padded};
    }
    mGrid = mParams.decomposition == Decomposition::Orsd ? grid : nullptr;

    const std::uint64_t triangleCount = triangles.count(); // building consumes the run file
    Result<PrototypeBuildResult> result = triangleCount > mChunkTriangles
            ? buildChunked(prototypeId, triangles, root, encoding, spillBytes)
            : buildInMemory(triangles, root, encoding);
    if (!result)
        return result.status().withContext("prototype " + std::to_string(prototypeId));
    // v1 stores every triangle it was given; v2 those the codec kept (what it reports).
    result->record.triangleCount = v2 ? result->recordV2.triangleCount : triangleCount;
    result->summary.rootCellSize = padded;
    return result;
}

Result<PrototypeBuildResult> PrototypeBuilder::buildInMemory(
        RunFile& triangles, const Cell& root, const PrototypeEncodingV2* encoding) {
    FF_ASSIGN_OR_RETURN(std::vector<storage::PackedTriangle> all, triangles.readAll());
    triangles.remove();
    BuiltHierarchy built = buildInMemoryHierarchy(all, root, 0, 0, mParams, mGrid);
    if (encoding != nullptr)
        return writeInMemoryV2(std::move(all), std::move(built), *encoding);
    const glm::vec3 boundsMin = built.nodes[0].boundsMin;
    const glm::vec3 boundsMax = built.nodes[0].boundsMax;
    PrototypeBuildResult result;
    result.nodes = built.nodes.size();
    result.leafNodes = built.leafNodes;
    EncodedSubtree encoded = encodeSubtree(std::move(built.nodes), std::move(all), mWriter.pageSize());
    result.geometryPages = encoded.geometryPageCount(mWriter.pageSize());
    result.nodePages = encoded.nodePages.size();
    FF_RETURN_IF_ERROR(commitSubtree(mWriter, encoded));
    result.record.root = encoded.rootRef;
    result.record.boundsMin = {boundsMin.x, boundsMin.y, boundsMin.z};
    result.record.boundsMax = {boundsMax.x, boundsMax.y, boundsMax.z};
    result.record.nodeCount = result.nodes;
    result.summary = std::move(built.summary);
    result.maxDepth = encoded.maxLevel;
    result.chunks = 1;
    return result;
}

Result<PrototypeBuildResult> PrototypeBuilder::writeInMemoryV2(
        std::vector<storage::PackedTriangle> all, BuiltHierarchy built, const PrototypeEncodingV2& encoding) {
    const glm::vec3 boundsMin = built.nodes[0].boundsMin;
    const glm::vec3 boundsMax = built.nodes[0].boundsMax;
    SubtreeV2Input input;
    input.prototype = encoding.storedIndex;
    input.grid = &encoding.grid;
    input.rootParent = storage::rootParentV2({{boundsMin.x, boundsMin.y, boundsMin.z}, {boundsMax.x, boundsMax.y, boundsMax.z}});
    input.threads = mThreads;
    input.standIns = standInKinds(mParams);
    FF_RETURN_IF_ERROR(shapeLeavesV2(built.nodes, all, leafShapeV2(mParams, encoding, mThreads)));
    PrototypeBuildResult result;
    result.summary = std::move(built.summary);
    FF_ASSIGN_OR_RETURN(
            const SubtreeV2Result written,
            writeSubtreeV2(mWriter, *mNodePageTable, std::move(built.nodes), all, input));
    result.nodes = written.nodes;
    result.leafNodes = written.leafNodes;
    result.geometryPages = written.geometryPages;
    result.nodePages = written.nodePages;
    result.maxDepth = written.maxLevel;
    result.chunks = 1;
    result.clusters = written.clusters;
    result.standIns = written.standIns;
    result.standInClusters = written.standInClusters;
    result.standInCounts = written.standInCounts;
    result.record.boundsMin = input.rootParent.bounds.min;
    result.record.boundsMax = input.rootParent.bounds.max;
    result.record.nodeCount = written.nodes;
    result.recordV2.rootNode = written.rootNode;
    result.recordV2.bounds = input.rootParent.bounds;
    result.recordV2.grid = encoding.grid;
    result.recordV2.triangleCount = written.storedTriangles;
    result.recordV2.nodeCount = written.nodes;
    return result;
}

Result<PrototypeBuildResult> PrototypeBuilder::finishChunkedV2(
        PrototypeBuildResult result,
        std::vector<BuildNode> nodes,
        std::vector<storage::PackedTriangle> ownTriangles,
        const std::vector<std::int64_t>& chunkOf,
        LevelRegionsV2& levels,
        const PrototypeEncodingV2& encoding,
        std::uint64_t& spillBytes) {
    // The records below the chunk roots are stored relative to the roots' decoded bounds, so
    // the tree above the chunks is settled (its small subtrees made leaves) before they are
    // written, and written after them (it names where their children went).
    FF_RETURN_IF_ERROR(shapeLeavesV2(nodes, ownTriangles, leafShapeV2(mParams, encoding, mThreads)));
    const glm::vec3 boundsMin = nodes[0].boundsMin;
    const glm::vec3 boundsMax = nodes[0].boundsMax;
    const storage::DecodedNodeV2 rootParent =
            storage::rootParentV2({{boundsMin.x, boundsMin.y, boundsMin.z}, {boundsMax.x, boundsMax.y, boundsMax.z}});
    const std::vector<storage::DecodedNodeV2> decoded = decodedNodesV2(nodes, rootParent);
    std::vector<storage::DecodedNodeV2> rootBoxes(result.chunks);
    for (std::size_t n = 0; n < nodes.size(); ++n)
        if (chunkOf[n] >= 0)
            rootBoxes.at(static_cast<std::size_t>(chunkOf[n])) = decoded[n];
    FF_RETURN_IF_ERROR(levels.finish(rootBoxes, [this](std::uint64_t done, std::uint64_t total) {
        report("layout", done, total);
    }));
    std::vector<PlacedNodeV2> placed;
    for (std::size_t n = 0; n < nodes.size(); ++n)
        if (chunkOf[n] >= 0)
            placed.push_back(levels.placedRoot(static_cast<std::size_t>(chunkOf[n]), static_cast<std::uint32_t>(n)));

    SubtreeV2Input input;
    input.prototype = encoding.storedIndex;
    input.grid = &encoding.grid;
    input.rootParent = rootParent;
    input.placed = placed;
    input.threads = mThreads;
    input.standIns = standInKinds(mParams);
    FF_ASSIGN_OR_RETURN(
            const SubtreeV2Result written,
            writeSubtreeV2(mWriter, *mNodePageTable, std::move(nodes), ownTriangles, input));
    result.clusters += written.clusters;
    result.standIns += written.standIns + levels.standIns();
    result.standInClusters += written.standInClusters;
    result.standInClusters += levels.standInStats();
    result.standInCounts += written.standInCounts;
    result.nodes = written.nodes + levels.nodes(); // the chunk roots are the tree above's
    result.leafNodes = written.leafNodes + levels.leafNodes();
    result.geometryPages = written.geometryPages + levels.geometryPages();
    result.nodePages = written.nodePages + levels.nodePages();
    result.maxDepth = std::max(written.maxLevel, levels.maxLevel());
    spillBytes += levels.spillBytes();
    result.record.boundsMin = rootParent.bounds.min;
    result.record.boundsMax = rootParent.bounds.max;
    result.record.nodeCount = result.nodes;
    result.recordV2.rootNode = written.rootNode;
    result.recordV2.bounds = rootParent.bounds;
    result.recordV2.grid = encoding.grid;
    result.recordV2.triangleCount = written.storedTriangles + levels.storedTriangles();
    result.recordV2.nodeCount = result.nodes;
    return result;
}

Result<PrototypeBuildResult> PrototypeBuilder::buildChunked(
        std::uint32_t prototypeId,
        RunFile& triangles,
        const Cell& root,
        const PrototypeEncodingV2* encoding,
        std::uint64_t& spillBytes) {
    // ---- count: triangles per cell at a level fine enough that cells fit a chunk -----------
    // A triangle is counted down to the cell it stops at (the first cell it is wider than, the
    // octree's large-triangle rule, with the same float cell sizes as octantCell()), so a cell
    // whose triangles all stop above it gets no count and hence no (empty) chunk. A cluster
    // denser than the chosen level resolves is counted again at a finer level.
    std::vector<TopNode> top;
    std::vector<std::uint32_t> chunkNodes; // top-node index of each chunk, in Morton order
    const std::uint64_t triangleCount = triangles.count();
    int countLevel = chooseCountLevel(triangleCount, mChunkTriangles);
    while (true) {
        std::vector<std::unordered_map<std::uint64_t, std::uint64_t>> counts(static_cast<std::size_t>(countLevel + 1));
        std::uint64_t counted = 0;
        FF_RETURN_IF_ERROR(triangles.forEachBatch(1u << 15, [&](std::span<const storage::PackedTriangle> batch) {
            counted += batch.size();
            report("count", counted, triangleCount);
            for (const storage::PackedTriangle& t : batch) {
                const float size = extent(t);
                float cellSize = root.size;
                int stop = 0;
                while (stop < countLevel && !(size > mParams.largeTriangleTolerance * cellSize)) {
                    cellSize *= 0.5f;
                    ++stop;
                }
                const std::uint64_t key = cellKey(root, centroid(t), countLevel) >> (3 * (countLevel - stop));
                ++counts[static_cast<std::size_t>(stop)][key];
            }
            return Status::ok();
        }));
        for (int l = countLevel - 1; l >= 0; --l)
            for (const auto& [key, count] : counts[static_cast<std::size_t>(l + 1)])
                counts[static_cast<std::size_t>(l)][key >> 3] += count;

        // ---- select chunks top-down: the largest cells that fit -----------------------------
        top.clear();
        chunkNodes.clear();
        top.emplace_back();
        top[0].cell = root;
        Status selectStatus = Status::ok();
        auto select = [&](auto&& self, std::uint32_t index) -> void {
            const TopNode node = {top[index].cell, top[index].level, top[index].octant, top[index].key, 0, 0, -1, {}};
            const std::uint64_t count = counts[static_cast<std::size_t>(node.level)][node.key];
            if (count <= mChunkTriangles) {
                top[index].chunk = static_cast<std::int64_t>(chunkNodes.size());
                chunkNodes.push_back(index);
                return;
            }
            if (node.level == countLevel) {
                selectStatus = Status(
                        ErrorCode::OutOfBudget,
                        "a cell of " + std::to_string(count) + " triangles at octree level " + std::to_string(node.level) +
                                " does not fit the per-chunk budget of " + std::to_string(mChunkTriangles) +
                                " triangles; raise --memory-budget");
                return;
            }
            std::vector<int> octants;
            for (int o = 0; o < 8; ++o)
                if (counts[static_cast<std::size_t>(node.level + 1)].count((node.key << 3) | static_cast<std::uint64_t>(o)))
                    octants.push_back(o);
            const auto first = static_cast<std::uint32_t>(top.size());
            top[index].firstChild = first;
            top[index].childCount = static_cast<std::uint32_t>(octants.size());
            for (int o : octants) {
                TopNode child;
                child.cell = node.cell.octantCell(o);
                child.level = node.level + 1;
                child.octant = o;
                child.key = (node.key << 3) | static_cast<std::uint64_t>(o);
                top.push_back(std::move(child));
            }
            for (std::uint32_t c = 0; c < octants.size() && selectStatus.isOk(); ++c)
                self(self, first + c);
        };
        select(select, 0);
        if (selectStatus.isOk())
            break;
        if (countLevel == kMaxCountLevel)
            return selectStatus;
        countLevel = std::min(countLevel + 3, kMaxCountLevel);
    }

    // ---- distribute: each triangle to its chunk's run file, or to the top cell it stops at --
    std::vector<RunFile> chunkFiles;
    chunkFiles.reserve(chunkNodes.size());
    const std::size_t bufferBytes = std::clamp<std::size_t>(
            static_cast<std::size_t>(mChunkTriangles * sizeof(storage::PackedTriangle) / 4 / std::max<std::size_t>(chunkNodes.size(), 1)),
            4096,
            1u << 20);
    for (std::size_t c = 0; c < chunkNodes.size(); ++c) {
        chunkFiles.emplace_back(
                mTempDirectory / ("proto" + std::to_string(prototypeId) + "-chunk" + std::to_string(c) + ".run"),
                mSpillCodec);
        chunkFiles.back().setBufferLimit(bufferBytes);
    }
    // The run file is consumed: its space comes back behind the reader, so the triangles need
    // the disk once while they move to the chunk files, not twice.
    std::uint64_t topTriangles = 0;
    std::uint64_t distributed = 0;
    FF_RETURN_IF_ERROR(triangles.consumeBatches(1u << 15, [&](std::span<const storage::PackedTriangle> batch) -> Status {
        distributed += batch.size();
        report("partition", distributed, triangleCount);
        for (const storage::PackedTriangle& t : batch) {
            const std::uint64_t key = cellKey(root, centroid(t), countLevel);
            const float size = extent(t);
            std::uint32_t index = 0;
            while (true) {
                TopNode& node = top[index];
                // A chunk takes every triangle that reaches it: its own octree keeps the ones
                // wider than its cell at its root. (Kept here, they would hang off a node that
                // is written from the chunk's record, and be lost.)
                if (node.chunk >= 0) {
                    FF_RETURN_IF_ERROR(chunkFiles[static_cast<std::size_t>(node.chunk)].append(std::span(&t, 1)));
                    break;
                }
                if (size > mParams.largeTriangleTolerance * node.cell.size) {
                    node.own.push_back(t);
                    if (++topTriangles > mChunkTriangles)
                        return Status(ErrorCode::OutOfBudget, "too many large triangles above the chunk level; raise --memory-budget");
                    break;
                }
                const auto octant = static_cast<int>((key >> (3 * (countLevel - node.level - 1))) & 7u);
                std::uint32_t next = 0;
                for (std::uint32_t c = 0; c < node.childCount; ++c)
                    if (top[node.firstChild + c].octant == octant)
                        next = node.firstChild + c;
                if (next == 0) // every counted cell has a path; if not, fail rather than loop
                    return Status(ErrorCode::Internal, "partitioning lost the path of a counted cell");
                index = next;
            }
        }
        return Status::ok();
    }).status()); // the run file is gone now; its bytes were counted by the caller
    for (RunFile& file : chunkFiles) {
        FF_RETURN_IF_ERROR(file.flush());
        spillBytes += file.bytesWritten();
    }

    // ---- build chunks on worker threads, place them in chunk order (deterministic output) ---
    // A chunk written on its own starts new pages: each chunk a frame enters would cost at
    // least a node page and a geometry page however little of it the frame needs, a cost that
    // grows with the number of chunks, that is with the scene (docs/results/paging.md). So the
    // chunks are laid out level by level across all of them (LevelRegions), and each chunk's
    // root waits in memory for the cells above the chunks: the whole prototype then shares
    // pages level by level, as if it had been built in one piece.
    PrototypeBuildResult result;
    result.chunks = chunkNodes.size();
    const std::string prefix = "proto" + std::to_string(prototypeId);
    LevelRegions levels(mWriter, mTempDirectory, mSpillCodec, prefix, mLevelExtentBytes);
    std::optional<LevelRegionsV2> levelsV2;
    if (encoding != nullptr)
        levelsV2.emplace(mWriter, *mNodePageTable, mTempDirectory, mSpillCodec, prefix, encoding->storedIndex);
    const std::optional<PrototypeEncodingV2> chunkEncoding =
            encoding != nullptr ? std::optional(*encoding) : std::nullopt;
    std::vector<BuildNode> chunkRoots(chunkNodes.size()); // for the top tree
    for (std::size_t begin = 0; begin < chunkNodes.size(); begin += mThreads) {
        const std::size_t end = std::min<std::size_t>(begin + mThreads, chunkNodes.size());
        std::vector<std::future<Result<ChunkOutput>>> running;
        for (std::size_t c = begin; c < end; ++c) {
            const TopNode& node = top[chunkNodes[c]];
            RunFile* file = &chunkFiles[c];
            const Cell cell = node.cell;
            const int level = node.level;
            const int octant = node.octant;
            const HierarchyParams params = mParams;
            running.push_back(std::async(std::launch::async, [file, cell, level, octant, params, grid = mGrid, chunkEncoding, pageSize = mWriter.pageSize()]() -> Result<ChunkOutput> {
                FF_ASSIGN_OR_RETURN(std::vector<storage::PackedTriangle> chunkTriangles, file->readAll());
                file->remove();
                return buildChunk(
                        std::move(chunkTriangles), cell, level, octant, params, grid, chunkEncoding, pageSize);
            }));
        }
        for (std::size_t c = begin; c < end; ++c) {
            Result<ChunkOutput> chunk = running[c - begin].get();
            if (!chunk)
                return chunk.status();
            if (levelsV2) {
                result.clusters += chunk->clusters->stats;
                result.standInCounts += chunk->standInCounts;
                FF_RETURN_IF_ERROR(levelsV2->append(chunk->encoded, *chunk->clusters));
            }
            else
                FF_RETURN_IF_ERROR(levels.append(chunk->encoded));
            result.nodes += chunk->encoded.nodeCount + 1; // and its root
            result.leafNodes += chunk->leafNodes;
            result.maxDepth = std::max(result.maxDepth, chunk->encoded.maxLevel);
            for (std::size_t l = 0; l < chunk->summary.cuts.size(); ++l) {
                auto& cut = result.summary.cuts[l];
                cut.insert(cut.end(), chunk->summary.cuts[l].begin(), chunk->summary.cuts[l].end());
            }
            chunkRoots[c] = std::move(chunk->encoded.root);
            report("chunks", c + 1, chunkNodes.size());
        }
    }
    const auto reportLayout = [this](std::uint64_t done, std::uint64_t total) {
        report("layout", done, total);
    };
    if (!levelsV2) {
        FF_RETURN_IF_ERROR(levels.finish(reportLayout));
        result.geometryPages += levels.geometryPages();
        result.nodePages += levels.nodePages();
        spillBytes += levels.spillBytes();
    }

    // ---- the top tree: cells above the chunks, composited from them --------------------------
    std::vector<BuildNode> nodes(top.size());
    std::vector<storage::PackedTriangle> ownTriangles;
    ownTriangles.reserve(topTriangles);
    for (std::size_t i = 0; i < top.size(); ++i) {
        TopNode& t = top[i];
        BuildNode& n = nodes[i];
        if (t.chunk >= 0) { // the chunk's root; its children and triangles are in the levels
            FF_ASSERT(t.own.empty()); // a chunk takes every triangle that reaches it
            n = std::move(chunkRoots[static_cast<std::size_t>(t.chunk)]);
            if (levelsV2) // placed by LevelRegionsV2 once the tree above is known
                continue;
            if (n.placedChildren)
                n.placedChildren = levels.absoluteChildren(n.level + 1u, *n.placedChildren);
            if (n.placedTriangles)
                n.placedTriangles = levels.absoluteTriangles(n.level, *n.placedTriangles);
            continue;
        }
        n.cellMin = t.cell.min;
        n.cellMax = t.cell.max();
        n.level = static_cast<std::uint8_t>(t.level);
        n.octant = static_cast<std::uint8_t>(t.octant);
        n.firstChild = t.firstChild;
        n.childCount = t.childCount;
        n.octreeChildren = t.childCount > 0;
        n.firstTriangle = ownTriangles.size();
        n.triangleCount = t.own.size();
        ownTriangles.insert(ownTriangles.end(), t.own.begin(), t.own.end());
        t.own = {};
    }
    // Children come after their parents in `top`, so a reverse sweep is a post-order.
    CubeBaker baker(mParams.bakeResolution);
    for (std::size_t r = top.size(); r-- > 0;) {
        BuildNode& n = nodes[r];
        if (top[r].chunk >= 0)
            continue;
        n.boundsMin = glm::vec3(std::numeric_limits<float>::infinity());
        n.boundsMax = glm::vec3(-std::numeric_limits<float>::infinity());
        const auto own = std::span(ownTriangles).subspan(n.firstTriangle, n.triangleCount);
        for (const storage::PackedTriangle& t : own)
            growBounds(n.boundsMin, n.boundsMax, t);
        std::array<const ColorCube*, 8> children{};
        for (std::uint32_t c = 0; c < n.childCount; ++c) {
            const BuildNode& child = nodes[n.firstChild + c];
            children[child.octant] = &child.cube;
            n.boundsMin = glm::min(n.boundsMin, child.boundsMin);
            n.boundsMax = glm::max(n.boundsMax, child.boundsMax);
        }
        baker.reset(n.cellMin, n.cellMax);
        baker.addTriangles(own);
        const QuadrantColors underlay = compositeOctantQuadrants(children);
        n.cube = baker.finish(&underlay);
    }
    for (std::size_t i = 0; i < top.size(); ++i)
        if (top[i].chunk < 0) // a chunk summarised its own nodes
            addToSummary(nodes[i], result.summary);
    const glm::vec3 boundsMin = nodes[0].boundsMin;
    const glm::vec3 boundsMax = nodes[0].boundsMax;
    if (levelsV2)
    {
        std::vector<std::int64_t> chunkOf(top.size());
        for (std::size_t i = 0; i < top.size(); ++i)
            chunkOf[i] = top[i].chunk;
        return finishChunkedV2(std::move(result), std::move(nodes), std::move(ownTriangles), chunkOf, *levelsV2, *encoding, spillBytes);
    }
    EncodedSubtree encoded = encodeSubtree(std::move(nodes), std::move(ownTriangles), mWriter.pageSize());
    result.geometryPages += encoded.geometryPageCount(mWriter.pageSize());
    result.nodePages += encoded.nodePages.size();
    result.nodes += encoded.nodeCount - chunkNodes.size(); // the roots were counted with their chunks
    FF_RETURN_IF_ERROR(commitSubtree(mWriter, encoded));
    result.record.root = encoded.rootRef;
    result.record.boundsMin = {boundsMin.x, boundsMin.y, boundsMin.z};
    result.record.boundsMax = {boundsMax.x, boundsMax.y, boundsMax.z};
    result.record.nodeCount = result.nodes;
    return result;
}

} // namespace ff::builder
