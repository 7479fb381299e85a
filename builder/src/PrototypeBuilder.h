#pragma once

#include "OctreeBuilder.h"
#include "RunFile.h"

#include <ff/builder/ColorCube.h>
#include <ff/builder/SceneBuilder.h>
#include <ff/storage/SceneWriter.h>
#include <ff/storage/Status.h>

#include <array>
#include <cstdint>
#include <filesystem>
#include <vector>

namespace ff::builder {

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
    storage::PrototypeRecord record{};
    PrototypeSummary summary;
    std::uint64_t nodes = 0;
    std::uint32_t maxDepth = 0;
    std::uint64_t chunks = 0;
    std::uint64_t geometryPages = 0;
    std::uint64_t nodePages = 0;
};

/** Bytes of memory the builder plans per triangle of a chunk (triangle, nodes, records). */
inline constexpr std::uint64_t kChunkBytesPerTriangle = 160;

/**
 * Builds one prototype's octree from its run file and appends its pages to `writer`. A
 * prototype larger than one chunk (chunkTriangles) is partitioned out of core first, and its
 * chunks are laid out level by level across all of them (LevelRegions). Each chunk's top
 * levels (its crown, at most a page of records and crownBytes across all chunks) are held back
 * and written with the cells above the chunks, in one breadth-first order.
 */
class PrototypeBuilder {
public:
    PrototypeBuilder(
            storage::SceneWriter& writer,
            const HierarchyParams& params,
            std::uint64_t chunkTriangles,
            std::uint64_t crownBytes,
            unsigned threads,
            std::filesystem::path tempDirectory);

    /** Builds and writes the prototype in `triangles` (consumed). Adds the bytes of the chunk
     *  files it writes to `spillBytes`; the run file itself is the caller's to count. */
    [[nodiscard]] Result<PrototypeBuildResult> build(
            std::uint32_t prototypeId,
            RunFile& triangles,
            const glm::vec3& boundsMin,
            const glm::vec3& boundsMax,
            std::uint64_t& spillBytes);

private:

    [[nodiscard]] Result<PrototypeBuildResult> buildInMemory(RunFile& triangles, const Cell& root);
    [[nodiscard]] Result<PrototypeBuildResult> buildChunked(
            std::uint32_t prototypeId, RunFile& triangles, const Cell& root, std::uint64_t& spillBytes);

    storage::SceneWriter& mWriter;
    const HierarchyParams& mParams;
    std::uint64_t mChunkTriangles;
    std::uint64_t mCrownBytes; ///< memory for the chunks' crowns, all chunks together
    unsigned mThreads;
    std::filesystem::path mTempDirectory;
};

} // namespace ff::builder
