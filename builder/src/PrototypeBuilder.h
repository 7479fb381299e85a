#pragma once

#include "OctreeBuilder.h"
#include "RunFile.h"
#include "SubtreeEncoderV2.h"

#include <ff/builder/ColorCube.h>
#include <ff/builder/SceneBuilder.h>
#include <ff/storage/PrototypeRecordV2.h>
#include <ff/storage/SceneWriter.h>
#include <ff/storage/Status.h>

#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <vector>

namespace ff::builder {

class LevelRegionsV2;

/** A prototype cell as the instance level sees it when baking its own cubes. */
struct SummaryBox {
    glm::vec3 cellMin{0.0f};
    glm::vec3 cellMax{0.0f};
    ColorCube cube;
};

/**
 * Cuts through a prototype's hierarchy: cuts[l] covers the prototype with the cells of level l
 * (and leaves above l), so the instance level can bake from boxes of a chosen size.
 */
struct PrototypeSummary {
    static constexpr int kDepth = 5;
    float rootCellSize = 0.0f;
    std::array<std::vector<SummaryBox>, kDepth + 1> cuts;
};

struct PrototypeBuildResult {
    storage::PrototypeRecord record{}; ///< v1's record; in a v2 build its root is not set
    storage::PrototypeV2 recordV2{};   ///< a v2 build's record
    ClusterBuildStats clusters;        ///< a v2 build's encoding
    std::uint64_t standIns = 0;        ///< a v2 build's stand-ins (StandIns.h)
    ClusterBuildStats standInClusters; ///< and their encoding
    StandInCounts standInCounts;       ///< what became of each cell that could have had one
    PrototypeSummary summary;
    std::uint64_t nodes = 0;
    std::uint64_t leafNodes = 0;
    std::uint32_t maxDepth = 0;
    std::uint64_t chunks = 0;
    std::uint64_t geometryPages = 0;
    std::uint64_t nodePages = 0;
};

/** A hierarchy built in memory, before it is written. */
struct BuiltHierarchy {
    std::vector<BuildNode> nodes; ///< nodes[0] is the root
    PrototypeSummary summary;
    std::uint64_t leafNodes = 0;
};

/** How a v2 build encodes one prototype's geometry. */
struct PrototypeEncodingV2 {
    storage::PositionGrid grid;      ///< its clusters' grid
    std::uint32_t storedIndex = 0;   ///< its index in the file's Prototypes section
    /** Its leaves' size and whether they are split into cluster nodes (HierarchyParams::leavesFor
     *  its placements and size). */
    PrototypeLeaves leaves;
};

/** Bytes of memory the builder plans per triangle of a chunk (triangle, nodes, records). */
inline constexpr std::uint64_t kChunkBytesPerTriangle = 160;
/** And what a bounding-volume decomposition adds: a SplitItem and an order index per triangle. */
inline constexpr std::uint64_t kDecompositionBytesPerTriangle = 44;

/**
 * Builds one prototype's hierarchy from its run file and appends its pages to `writer`. A
 * prototype larger than one chunk (chunkTriangles) is partitioned out of core first, and its
 * chunks are laid out level by level across all of them (LevelRegions). Each chunk's root is
 * held back and written with the cells above the chunks.
 *
 * A chunked build reports its progress through `progress`: "count" and "partition" (triangles
 * of the run file read, in each of the two passes), "chunks" (chunks placed) and "layout"
 * (node pages copied from the level files into the scene file).
 */
class PrototypeBuilder {
public:
    PrototypeBuilder(
            storage::SceneWriter& writer,
            const HierarchyParams& params,
            std::uint64_t chunkTriangles,
            std::uint64_t levelExtentBytes,
            unsigned threads,
            std::filesystem::path tempDirectory,
            SpillCodec spillCodec,
            std::function<void(const BuildProgress&)> progress = {},
            NodePageTable* nodePageTable = nullptr);

    /** Builds and writes the prototype in `triangles` (consumed); `grid`: the voxel grid its
     *  source declared, if any (ORSD needs one); `encoding`: how a v2 writer (the writer's
     *  formatVersion()) encodes its clusters, null for v1. Adds the bytes of the
     *  chunk files it writes to `spillBytes`; the run file itself is the caller's to count. */
    [[nodiscard]] Result<PrototypeBuildResult> build(
            std::uint32_t prototypeId,
            RunFile& triangles,
            const glm::vec3& boundsMin,
            const glm::vec3& boundsMax,
            const VoxelGrid* grid,
            const PrototypeEncodingV2* encoding,
            std::uint64_t& spillBytes);

private:

    /** Reads the prototype, builds its hierarchy in memory and writes it: format 1, or format 2
     *  with `encoding`. */
    [[nodiscard]] Result<PrototypeBuildResult>
    buildInMemory(RunFile& triangles, const Cell& root, const PrototypeEncodingV2* encoding);
    [[nodiscard]] Result<PrototypeBuildResult> writeInMemoryV2(
            std::vector<storage::PackedTriangle> all, BuiltHierarchy built, const PrototypeEncodingV2& encoding);
    [[nodiscard]] Result<PrototypeBuildResult> buildChunked(
            std::uint32_t prototypeId,
            RunFile& triangles,
            const Cell& root,
            const PrototypeEncodingV2* encoding,
            std::uint64_t& spillBytes);
    /** Format 2's end of a chunked build: the tree above the chunks (`chunkOf[n]`: the chunk
     *  node n is the root of, or -1), then the chunks' level regions, then that tree. */
    [[nodiscard]] Result<PrototypeBuildResult> finishChunkedV2(
            PrototypeBuildResult result,
            std::vector<BuildNode> nodes,
            std::vector<storage::PackedTriangle> ownTriangles,
            const std::vector<std::int64_t>& chunkOf,
            LevelRegionsV2& levels,
            const PrototypeEncodingV2& encoding,
            std::uint64_t& spillBytes);

    storage::SceneWriter& mWriter;
    const HierarchyParams& mParams;
    std::uint64_t mChunkTriangles;
    std::uint64_t mLevelExtentBytes; ///< memory per octree level for triangles on their way out (LevelRegions)
    unsigned mThreads;
    std::filesystem::path mTempDirectory;
    SpillCodec mSpillCodec;
    std::function<void(const BuildProgress&)> mProgress;
    NodePageTable* mNodePageTable = nullptr; ///< a v2 build's Nodes pages
    const VoxelGrid* mGrid = nullptr; ///< ORSD: the grid of the prototype being built

    void report(const char* phase, std::uint64_t done, std::uint64_t total) const {
        if (mProgress)
            mProgress({phase, done, total});
    }
};

} // namespace ff::builder
