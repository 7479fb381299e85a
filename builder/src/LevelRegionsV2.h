#pragma once

// LevelRegions for format 2: the chunks of a partitioned prototype below their roots, laid out
// level by level across all chunks (each octree level's records of every chunk in one region of
// node pages, in chunk order; their clusters in that level's cluster pages), so a level shares
// pages across chunk boundaries as in a prototype built in one piece (LevelRegions.h says why).
//
// Version 2 stores a record's bounds relative to its parent's decoded bounds, so the regions are
// written top-down once the tree above the chunks is known: finish() takes the decoded bounds of
// every chunk's root. Records wait in one spill file per level (48 bytes of record and a few
// words of references each); clusters are encoded on the chunk's worker thread
// (encodeChunkClusters) and go straight to each level's cluster pages.

#include "ClusterPagePacker.h"
#include "OctreeBuilder.h"
#include "PendingNodeV2.h"
#include "RunFile.h"
#include "SubtreeEncoder.h"
#include "SubtreeEncoderV2.h"

#include <ff/builder/ClusterBuild.h>
#include <ff/builder/SpillCodec.h>
#include <ff/storage/ClusterCodec.h>
#include <ff/storage/NodeRecordV2.h>
#include <ff/storage/SceneWriter.h>
#include <ff/storage/Status.h>

#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace ff::builder {

/** One node's clusters within its level's encoded bytes. */
struct EncodedRun {
    std::uint64_t offset = 0; ///< in the level's bytes
    std::uint64_t bytes = 0;
    std::uint32_t clusters = 0;
    std::uint64_t kept = 0; ///< triangles the codec kept
    std::uint64_t unlit = 0; ///< of them, unlit
    float error = 0.0f;      ///< a stand-in's (StandIns.h)
    storage::RepresentationKind kind = storage::RepresentationKind::Clusters; ///< a stand-in's
};

/** A chunk's clusters, level by level, encoded on its worker thread. */
struct ChunkClustersV2 {
    struct Level {
        std::vector<std::byte> bytes;
        std::vector<EncodedRun> runs; ///< one per record of the level, in order
        /** Per record, its stand-in's clusters (none: no clusters); empty if none has one. */
        std::vector<EncodedRun> standIns;
    };
    std::vector<Level> levels; ///< as LevelledSubtree::levels
    EncodedRun root;           ///< the root's own triangles, in levels[0].bytes
    EncodedRun rootStandIn;    ///< the root's stand-in, in levels[0].bytes
    ClusterBuildStats stats;   ///< the nodes' own triangles
    ClusterBuildStats standInStats;
    std::uint64_t standIns = 0;
};

/** Encodes every record's triangles of `chunk` (and its root's) into clusters on `grid`, and
 *  their stand-ins, then frees the chunk's triangles and stand-ins. Thread-safe for different
 *  chunks. */
[[nodiscard]] Result<ChunkClustersV2>
encodeChunkClusters(LevelledSubtree& chunk, const storage::PositionGrid& grid);

/** Not thread-safe; while it lives only it and `table` append Nodes pages to the writer. */
class LevelRegionsV2 {
public:
    LevelRegionsV2(
            storage::SceneWriter& writer,
            NodePageTable& table,
            std::filesystem::path directory,
            SpillCodec codec,
            std::string prefix,
            std::uint32_t storedPrototype);
    ~LevelRegionsV2();
    LevelRegionsV2(const LevelRegionsV2&) = delete;
    LevelRegionsV2& operator=(const LevelRegionsV2&) = delete;

    /** Places the chunk after those appended before it: its clusters into their levels' pages
     *  (written as they fill), its records into their levels' spill files. Frees both. */
    [[nodiscard]] Status append(LevelledSubtree& chunk, ChunkClustersV2& clusters);

    /**
     * Writes the open cluster pages, then every level's node pages top-down, each record
     * read against its parent's decoded bounds and cell; `rootBoxes[c]` is what the c-th
     * appended chunk's root decodes to (decodedNodesV2 of the tree above the chunks). Then
     * placedRoot() says where each root's children and payload went.
     */
    [[nodiscard]] Status
    finish(std::span<const storage::DecodedNodeV2> rootBoxes,
           const std::function<void(std::uint64_t done, std::uint64_t total)>& pagesWritten = {});

    /** After finish(): what the record of chunk `chunk`'s root (node `node` of the tree above)
     *  needs. */
    [[nodiscard]] PlacedNodeV2 placedRoot(std::size_t chunk, std::uint32_t node) const;

    [[nodiscard]] std::uint64_t nodes() const noexcept { return mNodes; }
    [[nodiscard]] std::uint64_t leafNodes() const noexcept { return mLeafNodes; }
    [[nodiscard]] std::uint64_t storedTriangles() const noexcept { return mStoredTriangles; }
    [[nodiscard]] std::uint64_t standIns() const noexcept { return mStandIns; }
    [[nodiscard]] const ClusterBuildStats& standInStats() const noexcept { return mStandInStats; }
    [[nodiscard]] std::uint64_t nodePages() const noexcept;
    [[nodiscard]] std::uint64_t geometryPages() const noexcept;
    [[nodiscard]] std::uint64_t spillBytes() const noexcept;
    [[nodiscard]] std::uint32_t maxLevel() const noexcept { return mMaxLevel; }

private:
    struct Region;
    struct Root {
        std::uint32_t level = 0;
        std::uint32_t firstChild = 0; ///< position in region level + 1
        std::uint32_t childCount = 0;
        std::vector<storage::RepresentationRecord>
                representations; ///< local pages of region `level`
        std::uint64_t storedTriangles = 0;
        StandInSource standInSource = StandInSource::unusable(); ///< for a stand-in above it
        double drawnTriangles = 0.0;
        double unlitTriangles = 0.0; ///< of drawnTriangles
        std::uint32_t absoluteFirstChild = 0; ///< set by finish()
    };

    Region& region(std::uint32_t level);
    [[nodiscard]] Status writeRegion(std::size_t level, const std::function<void()>& pageWritten);

    storage::SceneWriter& mWriter;
    NodePageTable& mTable;
    std::filesystem::path mDirectory;
    SpillCodec mCodec;
    std::string mPrefix;
    std::uint32_t mPrototype;
    std::vector<std::unique_ptr<Region>> mRegions; ///< by octree level
    std::vector<Root> mRoots;                      ///< by chunk
    std::uint64_t mNodes = 0;
    std::uint64_t mLeafNodes = 0;
    std::uint64_t mStoredTriangles = 0;
    std::uint64_t mStandIns = 0;
    ClusterBuildStats mStandInStats;
    std::uint32_t mMaxLevel = 0;
};

} // namespace ff::builder
