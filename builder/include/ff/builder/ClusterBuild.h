#pragma once

// One node's triangles as compact clusters: positions quantized on the prototype's grid,
// identical vertices merged, the index buffer split into meshlets (meshopt_buildMeshlets) and
// each meshlet ordered for the vertex cache and encoded (storage/ClusterCodec.h).

#include <ff/storage/ClusterCodec.h>
#include <ff/storage/SceneFormat.h>
#include <ff/storage/Status.h>

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace ff::builder {

/** Cluster limits; meshopt 0.18 allows at most 255 vertices and 512 triangles (a multiple of 4). */
struct ClusterLimits {
    std::uint32_t maxVertices = 128;
    std::uint32_t maxTriangles = 256;
};

/** What encoding a node's triangles made. */
struct ClusterBuildStats {
    std::uint64_t clusters = 0;
    std::uint64_t trianglesIn = 0;
    std::uint64_t trianglesKept = 0;   ///< after dropping those quantization collapsed
    std::uint64_t trianglesUnlit = 0;  ///< of those kept, with three unlit corners
    std::uint64_t uniqueVertices = 0;  ///< after merging identical quantized vertices
    std::uint64_t clusterVertices = 0; ///< vertices over all clusters (shared ones repeat)
    std::uint64_t encodedBytes = 0;
    std::uint64_t wideClusters = 0;
    std::uint64_t points = 0; ///< splats, in point clusters (encodePoints)

    ClusterBuildStats& operator+=(const ClusterBuildStats& other) noexcept;
};

/**
 * Appends the clusters of `triangles` to `out`, one after the other (each starts with its
 * header: storage::readClusterInfo walks them), and returns what it made. A triangle whose
 * corners quantize onto fewer than three grid points draws nothing and is dropped. The same
 * input always gives the same bytes; the encoder keeps its scratch memory for the next call.
 */
class ClusterEncoder {
public:
    explicit ClusterEncoder(ClusterLimits limits = {});

    [[nodiscard]] Result<ClusterBuildStats>
    encode(std::span<const storage::PackedTriangle> triangles,
           const storage::PositionGrid& grid,
           std::vector<std::byte>& out);

    /** Appends `points` (splats) as point clusters of up to 255, in spatial order (the vertex
     *  codec stores neighbours' small deltas), positions quantized on `grid`. */
    [[nodiscard]] Result<ClusterBuildStats>
    encodePoints(std::span<const storage::PackedVertex> points,
                 const storage::PositionGrid& grid,
                 std::vector<std::byte>& out);

    /** How many clusters encode() makes of `triangles`, without encoding them. */
    [[nodiscard]] Result<std::uint32_t>
    countClusters(std::span<const storage::PackedTriangle> triangles, const storage::PositionGrid& grid);

private:
    /** Quantizes and merges the corners, drops collapsed triangles and splits the rest into
     *  meshlets (mMeshlets, mMeshletVertices, mMeshletTriangles). Returns the meshlet count. */
    [[nodiscard]] Result<std::size_t>
    buildMeshlets(std::span<const storage::PackedTriangle> triangles,
                  const storage::PositionGrid& grid,
                  ClusterBuildStats& stats);

    /** A meshlet's ranges in mMeshletVertices and mMeshletTriangles. */
    struct Meshlet {
        std::uint32_t vertexOffset = 0;
        std::uint32_t triangleOffset = 0;
        std::uint32_t vertexCount = 0;
        std::uint32_t triangleCount = 0;
    };

    ClusterLimits mLimits;
    std::vector<storage::ClusterVertex> mCorners;
    std::vector<unsigned int> mRemap;
    std::vector<storage::ClusterVertex> mVertices;
    std::vector<float> mPositions;
    std::vector<unsigned int> mIndices;
    std::vector<Meshlet> mMeshlets;
    std::vector<unsigned int> mMeshletVertices;
    std::vector<unsigned char> mMeshletTriangles;
};

} // namespace ff::builder
