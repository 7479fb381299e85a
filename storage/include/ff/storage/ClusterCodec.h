#pragma once

// Compact geometry: one cluster (≤ 255 vertices, ≤ 512 triangles, indexed) encoded with
// meshoptimizer's vertex and index codecs, positions quantized on a grid shared by every cluster
// of a prototype so neighbouring clusters decode a shared vertex to the same float (no cracks).
// storage/FORMAT.md ("Cluster encoding") documents every byte.
//
// The decoders are free functions over bytes: memory-safe on truncation and garbage (every field
// is checked before it is used, and every decoded index and grid coordinate is range-checked, as
// meshoptimizer's decoders may turn garbage into out-of-range values).

#include <ff/storage/SceneFormat.h>
#include <ff/storage/Status.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

namespace ff::storage {

/** meshoptimizer's limits for one meshlet (meshopt_buildMeshlets), and so for a cluster. */
inline constexpr std::uint32_t kMaxClusterVertices = 255;
inline constexpr std::uint32_t kMaxClusterTriangles = 512;

/** Grid coordinates stay below 2^31 (a 10^9-triangle terrain at a thousandth of a triangle's
 *  edge needs 26 bits). */
inline constexpr int kMaxPositionGridBits = 31;
/** `covering()`'s default: 2^20 steps across the prototype's largest extent (position error at
 *  most 1/2^21 of it, half a step, plus float rounding). */
inline constexpr int kDefaultPositionGridBits = 20;

/** Normals are stored as octahedral codes of this many bits per component (PackedVertex keeps
 *  them as snorm16; the codec drops the low 4 bits). */
inline constexpr int kClusterNormalBits = 12;

/**
 * The quantization grid of one prototype: position = origin + step * coordinate, per axis, with
 * coordinates in [0, 2^bits), computed in double and rounded once to float, the same way
 * everywhere: one coordinate always decodes to one float, so clusters sharing a vertex never
 * crack.
 */
struct PositionGrid {
    std::array<float, 3> origin{0.0f, 0.0f, 0.0f};
    float step = 1.0f;
    int bits = kDefaultPositionGridBits;

    /** The grid of `bits` bits whose cube starts at boundsMin and covers boundsMax. Finite
     *  bounds, bits in [1, kMaxPositionGridBits]. */
    [[nodiscard]] static Result<PositionGrid> covering(
            std::array<float, 3> boundsMin,
            std::array<float, 3> boundsMax,
            int bits = kDefaultPositionGridBits);
    /** The grid of steps `step` from boundsMin that covers boundsMax: as many bits as that
     *  takes (an error if more than kMaxPositionGridBits). For a precision target in scene
     *  units, whatever the extent. */
    [[nodiscard]] static Result<PositionGrid>
    withStep(std::array<float, 3> boundsMin, std::array<float, 3> boundsMax, float step);

    /** The nearest grid coordinate (clamped into the grid). */
    [[nodiscard]] std::array<std::uint32_t, 3>
    quantize(std::array<float, 3> position) const noexcept;
    /** The position a coordinate stands for. */
    [[nodiscard]] std::array<float, 3>
    position(std::array<std::uint32_t, 3> coordinate) const noexcept;
    /** Largest distance per axis between a position inside the grid's cube and what its
     *  coordinate decodes to: half a step, plus the float rounding of the decode. */
    [[nodiscard]] float maxError() const noexcept;
};

/** A cluster's vertex as the encoder takes it. */
struct ClusterVertex {
    std::array<std::uint32_t, 3> coordinate; ///< PositionGrid coordinate
    std::array<std::int16_t, 2> normalOct;   ///< snorm16 octahedral (VertexCodec), kept to 12 bits
    std::array<std::uint8_t, 4> color;       ///< as PackedVertex::color
};

/** The snorm16 octahedral code a 12-bit code decodes to: what the codec keeps of `oct`
 *  (kUnlitNormalOct stays itself). */
[[nodiscard]] std::array<std::int16_t, 2>
roundNormalTo12Bits(std::array<std::int16_t, 2> oct) noexcept;

/** What a cluster's header says, checked against the bytes that hold it. */
struct ClusterInfo {
    std::uint32_t vertexCount = 0;
    std::uint32_t triangleCount = 0;
    std::uint32_t encodedBytes = 0; ///< header and both streams: where the next cluster starts
    bool widePositions = false;     ///< 32-bit coordinates (the cluster spans ≥ 2^16 steps)

    /** A point cluster (splats): vertices drawn as points, no triangles, no index stream. */
    [[nodiscard]] bool points() const noexcept { return triangleCount == 0; }
};

/** Encoded bytes a cluster of this size takes at most. */
[[nodiscard]] std::size_t
encodedClusterBound(std::size_t vertexCount, std::size_t triangleCount) noexcept;

/**
 * Encodes one cluster into `out` (at least encodedClusterBound() bytes) and returns the bytes
 * written. `indices` are 3 per triangle, each below vertices.size(); 1-255 vertices, 1-512
 * triangles, coordinates below 2^31. Deterministic: the same input gives the same bytes.
 * For the best compression, order triangles for the vertex cache and vertices by first use
 * (meshopt_optimizeVertexCache, meshopt_optimizeVertexFetch) before.
 */
[[nodiscard]] Result<std::size_t> encodeCluster(
        std::span<const ClusterVertex> vertices,
        std::span<const std::uint8_t> indices,
        std::span<std::byte> out);

/** Encodes a point cluster: 1-255 vertices, each a splat, no triangles and no index stream
 *  (FORMAT.md §6.3). As encodeCluster() otherwise; `out` at least encodedClusterBound(n, 0). */
[[nodiscard]] Result<std::size_t>
encodePointCluster(std::span<const ClusterVertex> vertices, std::span<std::byte> out);

/** Reads and checks the header of the cluster that starts `bytes`. */
[[nodiscard]] Result<ClusterInfo> readClusterInfo(std::span<const std::byte> bytes);

/**
 * Decodes the cluster that starts `bytes` into `vertices` (info.vertexCount) and `indices`
 * (3 per triangle, cluster-local), dequantized on `grid`. Triangles come back in their order
 * and winding, but each may start at another of its vertices (the index codec rotates them).
 * A corrupt cluster is an error, and whatever the spans hold then is garbage; so are spans too
 * small for the counts its header gives (Corrupt: they come from a table beside the cluster).
 */
[[nodiscard]] Status decodeCluster(
        std::span<const std::byte> bytes,
        const PositionGrid& grid,
        std::span<PackedVertex> vertices,
        std::span<std::uint8_t> indices);

} // namespace ff::storage
