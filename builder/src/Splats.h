#pragma once

// Static point splats (issue 17; Wand & Straßer 2002, §3.1-3.5, the static case): a cell may
// stand in for its subtree with opaque, depth-tested points spaced at a fixed fraction of the
// cell's size, plus the triangles too large to splat, drawn as they are.
//
// Chosen per cell from the triangles below it, as the paper does:
//  1. candidates: random surface points, triangles picked by area, n ln n x kSplatSafety of them
//     for n bins of diagonal spacing/8 (the coupon collector's bound: every bin a surface fully
//     covers gets one, with high probability), and points along every edge a bin's side apart
//     (bins the surface crosses without covering them), thinned to one per bin;
//  2. stratification: candidates deleted in random order while another within spacing/2 covers
//     them, never one that is the last cover of a point deleted before (no cascaded deletion);
//  3. attributes: each kept point's colour and normal a Gaussian average of the candidates
//     around it (a set some 70 x denser than the kept one);
//  4. a triangle that keeps more than kMaxSplatsPerTriangle points is drawn as a triangle (never
//     slower than rasterising it), and the splats are chosen again without it.
// Every surface point then lies within splatCoverRadius(spacing) of a splat (with high
// probability: the draws fill every fully covered bin only so): the splat set's error, which the
// runtime compares with ε, and whose double each point's diameter on screen must cover.

#include <ff/storage/ClusterCodec.h>
#include <ff/storage/SceneFormat.h>

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace ff::builder {

/** The candidate count's safety factor over the coupon collector's n ln n (the paper: 3-5). */
inline constexpr double kSplatSafety = 3.0;
/** A triangle that would keep more splats than this is drawn as a triangle instead. */
inline constexpr std::uint32_t kMaxSplatsPerTriangle = 3;
/** Splat sets with more candidate bins to fill are not built: memory (a bin's survivor, its
 *  attributes and cover count, ~80 bytes) and time (3 ln n draws a bin, 37 at this size, and
 *  the stratification's neighbour searches, thousands a survivor where a volume fills bins). */
inline constexpr std::size_t kMaxSplatBins = std::size_t{1} << 18;
/** A splat set must cost at most this share of the triangles it replaces (points and kept
 *  triangles together), as a stand-in must. */
inline constexpr double kMaxSplatShare = 0.6;
/** Default spacing: this fraction of a cell's largest side (`build --splat-spacing`). */
inline constexpr int kDefaultSplatSpacingDivisor = 8;

/** How far a surface point may lie from its nearest splat, for stratification at `spacing`:
 *  spacing/2 (stratification, from a bin's survivor to a splat) + at most two bin diagonals
 *  (spacing/8 each) and half a bin's side from a surface point to a survivor: in a bin the
 *  surface covers fully, the survivor is in its bin (one diagonal); in a bin an edge crosses,
 *  the point is a diagonal from the edge, the edge half a side from a sample, the sample a
 *  diagonal from its own bin's survivor. ~0.786 x spacing. */
constexpr float splatCoverRadius(float spacing) noexcept {
    constexpr float diagonal = 1.0f / 8.0f;
    constexpr float halfSide = diagonal / 1.7320508f / 2.0f;
    return (0.5f + 2.0f * diagonal + halfSide) * spacing;
}

/** A cell's splats and the triangles kept with them. */
struct SplatSet {
    std::vector<storage::PackedVertex> points;
    std::vector<storage::PackedTriangle> triangles;
    /** Hierarchy units: how far the drawn splats may lie from the subtree's own surface (the
     *  source's error plus splatCoverRadius). */
    float error = 0.0f;
};

/** Why a cell got no splat set (TooLarge: over kMaxSplatBins). */
enum class SplatOutcome : std::uint8_t { Kept, NotReducing, TooLarge, Empty };

/**
 * Stratifies `points` (Wand & Straßer §3.4.2): visits them in the order of `order` (a
 * permutation of their indices) and deletes each that another point not deleted lies within
 * `radius` of, unless it is the only such cover left of a point deleted before. Every deleted
 * point keeps a kept one within `radius`. Points must be finite. Returns the kept indices,
 * ascending.
 */
[[nodiscard]] std::vector<std::uint32_t> stratify(
        std::span<const std::array<float, 3>> points,
        std::span<const std::uint32_t> order,
        float radius);

/**
 * The splat set of `source` (a cell's triangles: own, and its children's stand-ins or
 * triangles) at `spacing` (hierarchy units) into `out`, positions snapped to `grid` as the
 * encoder will; `baseError` is the source's own error, `seed` makes the random choices
 * repeatable. Kept, or why not: it does not pay (over kMaxSplatShare of the source), would take
 * more than kMaxSplatBins bins, or there is no surface (`out` then unspecified).
 */
[[nodiscard]] SplatOutcome splatSource(
        std::span<const storage::PackedTriangle> source,
        float spacing,
        float baseError,
        const storage::PositionGrid& grid,
        std::uint64_t seed,
        SplatSet& out);

} // namespace ff::builder
