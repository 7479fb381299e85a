#pragma once

// Simplified stand-ins (issue 17's simplified clusters): a cell may carry a simplified copy of
// its whole subtree, drawn instead of it where the copy's error projects below ε pixels.
//
// Built bottom-up as Nanite builds its cluster groups: a node's source is its own triangles and
// each child's stand-in (or, where a child kept none, that child's source; a leaf below the
// root keeps none: its parent simplifies its triangles); the source is
// simplified with meshoptimizer (meshopt_simplify, its quadric error) with the mesh's border
// locked, to its ring of border triangles plus 0.22 of the source, and kept when that pays (at
// most 0.6 x). A cell's border is where its neighbours' triangles begin, so
// the edges there are the original ones on both sides, whatever level either side is drawn at:
// stand-ins never open cracks. Surface errors add up the tree (a node's is its children's
// largest plus its own step), shading errors do not (StandInSource), and a node's error is
// never below one under it.

#include "OctreeBuilder.h"

#include <ff/builder/ClusterBuild.h>
#include <ff/storage/NodeRecordV2.h>

#include <ff/storage/ClusterCodec.h>
#include <ff/storage/SceneFormat.h>
#include <ff/storage/Status.h>

#include <algorithm>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <vector>

namespace ff::builder {

/** What a node's parent simplifies from: the node's stand-in, or (none kept) its own triangles
 *  with its children's sources. */
struct StandInSource {
    std::vector<storage::PackedTriangle> triangles;
    /** Hierarchy units: how far `triangles` may lie from the subtree's own surface, summed up
     *  the tree (a bound: each level's simplification moves the last one's surface). */
    float error = 0.0f;
    /** False when the subtree is too large to simplify here (kMaxStandInSource) or holds an
     *  instance: no ancestor gets a stand-in. */
    bool usable = true;
    /** Hierarchy units: how far its shading may have drifted (StandInError.h), the largest of
     *  its levels', not their sum: a simplification keeps the original vertices it keeps, with
     *  their own colours and normals, and a level's drift is measured on the original vertices
     *  it removed (measured: methods §12). */
    float shadingError = 0.0f;

    /** The error a copy of it promises: the larger of the two. */
    float promised() const noexcept { return std::max(error, shadingError); }
    /** A subtree no ancestor simplifies (`usable` false). */
    static StandInSource unusable() { return {{}, 0.0f, false, 0.0f}; }
};

/** What a stand-in draws its subtree with. */
enum class StandInKind : std::uint8_t {
    Simplified, ///< a simplified copy of the subtree's triangles
    Splats,     ///< point splats and the triangles too large to splat (Splats.h)
};

/** A node's stand-in as written: what it draws and the error it promises. */
struct StandIn {
    std::vector<storage::PackedTriangle> triangles;
    float error = 0.0f;
    StandInKind kind = StandInKind::Simplified;
    std::vector<storage::PackedVertex> points; ///< Splats: the splats
    /** Simplified: its surface and shading errors (StandInSource; `error` is the larger), for
     *  the parent that simplifies it. */
    float surfaceError = 0.0f;
    float shadingError = 0.0f;
};

/** Which stand-ins a hierarchy's cells may get, and how a cell chooses among them. */
struct StandInKinds {
    bool simplified = true;
    /** Splats at 1/splatSpacing of the cell's largest side (Splats.h); 0: none. */
    int splatSpacing = 0;
    /** Each candidate's error measured against its source, and the one that pays best kept
     *  (StandInChoice.h); off: by rule, a simplified copy where one reduces, else splats. */
    bool measured = true;
};

/** Sources no larger than this are simplified (meshopt's memory is ~100 bytes a triangle). */
inline constexpr std::size_t kMaxStandInSource = 1u << 20;
/** Smaller sources are drawn as they are: a stand-in of a few dozen triangles saves nothing. */
inline constexpr std::size_t kMinStandInSource = 256;
/** A chunk's root hands at most this many triangles up to the tree above the chunks, which
 *  holds every chunk's at once (else the tree above gets no stand-ins): 1 MiB a chunk. */
inline constexpr std::size_t kMaxCarriedStandInSource = 1u << 14;
/** A stand-in must keep at most this share of its source's triangles (what its children
 *  draw), or it is not kept (issue 17: each level at most 0.6 x its children's). */
inline constexpr double kMaxStandInShare = 0.6;
/** The share of its source a stand-in aims for, on top of its ring of border triangles, which
 *  the border lock keeps whole at the leaves' density. With the ring inside the share (before),
 *  a far cell's ring took most of it and its interior was simplified the more: its errors grew
 *  up the tree faster than its cells, and the 4 M terrain's frame at issue 17's view drew 0.24 M
 *  triangles against 0.18 M with the ring on top (at a fifth). A quarter on top costs +50-52 %
 *  of the terrain's geometry bytes (issue 17 allows +50 %); a fifth +40-43 %, but the
 *  molecule's atoms (one-node prototypes, a fifth of a sphere) then showed their outlines
 *  2.25 dB below brute force at 2.5 radii (issue 17 allows 2; a quarter 1.40, 0.22 1.88). */
inline constexpr double kStandInTargetShare = 0.22;

/**
 * Simplifies `source` (welded on `grid`'s coordinates, so as the cluster encoder sees it) with
 * its border locked to its ring and kStandInTargetShare of its triangles, at most
 * kMaxStandInShare of them. nullopt when it keeps more than kMaxStandInShare. Its surface error is `source`'s plus the
 * simplification's, its shading error the larger of `source`'s and the simplification's.
 */
[[nodiscard]] std::optional<StandIn> simplifySource(const StandInSource& source, const storage::PositionGrid& grid);

/** Appends `standIn`'s clusters to `out`: its splats' point clusters, then its triangles'. */
[[nodiscard]] Result<ClusterBuildStats> encodeStandIn(
        ClusterEncoder& encoder,
        const StandIn& standIn,
        const storage::PositionGrid& grid,
        std::vector<std::byte>& out);

/** The representation kind a stand-in is stored as (FORMAT.md §5.3). */
constexpr storage::RepresentationKind representationKindOf(StandInKind kind) noexcept {
    return kind == StandInKind::Splats ? storage::RepresentationKind::Splats
                                       : storage::RepresentationKind::Clusters;
}

/** What became of the cells that could have had a stand-in (the build report's "why"). */
struct StandInCounts {
    std::uint64_t kept = 0;
    std::uint64_t notReducing = 0; ///< simplified to more than kMaxStandInShare: not kept
    std::uint64_t tooSmall = 0;    ///< leaves below the root, sources under kMinStandInSource
    std::uint64_t tooLarge = 0;    ///< sources over kMaxStandInSource or stand-ins over
                                   ///< StandInLimits::maxTriangles, or above an instance or a
                                   ///< chunk whose source was not handed up
    std::uint64_t splats = 0;      ///< of `kept`, cells that keep splats (no simplification paid)
    std::uint64_t splatsNotReducing = 0; ///< splat sets over kMaxSplatShare: not kept
    std::uint64_t splatsTooLarge = 0;    ///< splat sets over kMaxSplatBins candidate bins or a page limit
    /** Measured (StandInChoice.h): cells whose candidates kept their shape only where the cell
     *  spans under kMinStandInSpanPixels (none kept; counted once, like notReducing), splat sets
     *  that did not, kept stand-ins whose error the measure raised, and cells where both kinds
     *  paid and splats were kept. */
    std::uint64_t notPaying = 0;
    std::uint64_t splatsNotPaying = 0;
    std::uint64_t errorsRaised = 0;
    std::uint64_t splatsOverSimplified = 0;
    StandInCounts& operator+=(const StandInCounts& other) noexcept {
        notPaying += other.notPaying;
        splatsNotPaying += other.splatsNotPaying;
        errorsRaised += other.errorsRaised;
        splatsOverSimplified += other.splatsOverSimplified;
        splats += other.splats;
        splatsNotReducing += other.splatsNotReducing;
        splatsTooLarge += other.splatsTooLarge;
        kept += other.kept;
        notReducing += other.notReducing;
        tooSmall += other.tooSmall;
        tooLarge += other.tooLarge;
        return *this;
    }
};

/** What a hierarchy's stand-ins must keep to. */
struct StandInLimits {
    /** A larger stand-in is not kept: its representations (one a page) must fit its node's
     *  page beside its siblings' (maxStandInTriangles). */
    std::size_t maxTriangles = std::numeric_limits<std::size_t>::max();
    /** False for a chunk's root, which is a node below its prototype's root: a leaf there gets
     *  no stand-in either. */
    bool rootIsTop = true;
};

/** The largest stand-in a file of `pageSize` pages keeps: about eight cluster pages of it (at
 *  ~10 bytes a stand-in triangle), so a block of eight siblings with theirs fits a Nodes page. */
std::size_t maxStandInTriangles(std::uint32_t pageSize) noexcept;

/**
 * Stand-ins of a hierarchy (nodes[0] the root, children after their parents) of the `kinds`
 * asked for: one entry per node, set where a stand-in was kept. A cell's splats are made from
 * the source it would simplify (the parent's source is that source, not the splats). `placed` gives the sources of nodes whose subtrees were
 * built elsewhere (a chunk's root, by node index; absent: no source). `rootSource` gets the
 * root's source for a tree above; `counts` what became of each cell. Deterministic whatever
 * `threads`.
 */
struct PlacedSource {
    std::uint32_t node = 0;
    const StandInSource* source = nullptr;
};
[[nodiscard]] Result<std::vector<std::optional<StandIn>>> buildStandIns(
        const std::vector<BuildNode>& nodes,
        std::span<const storage::PackedTriangle> triangles,
        const storage::PositionGrid& grid,
        std::span<const PlacedSource> placed,
        unsigned threads,
        StandInSource* rootSource,
        StandInCounts& counts,
        const StandInLimits& limits = {},
        const StandInKinds& kinds = {});

} // namespace ff::builder
