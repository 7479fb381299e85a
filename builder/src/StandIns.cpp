#include "StandIns.h"

#include "ParallelFor.h"
#include "Splats.h"
#include "StandInChoice.h"
#include "StandInError.h"

#include <ff/storage/Assert.h>

#include <meshoptimizer.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <unordered_map>

namespace ff::builder {

namespace {

/** A corner as the cluster encoder merges it: its grid coordinate and attributes. */
struct WeldKey {
    std::array<std::uint32_t, 3> coordinate;
    std::array<std::int16_t, 2> normalOct;
    std::array<std::uint8_t, 4> color;
};
static_assert(sizeof(WeldKey) == 20); // no padding: meshopt compares its bytes

/** How many triangles of `indices` have an edge no other triangle uses: the mesh's ring of
 *  border triangles, which a border-locked simplification keeps. */
std::size_t borderTriangleCount(std::span<const unsigned> indices) {
    struct EdgeUse {
        std::uint64_t edge; // its ends, the smaller first
        std::size_t triangle;
    };
    std::vector<EdgeUse> uses;
    uses.reserve(indices.size());
    for (std::size_t t = 0; t < indices.size() / 3; ++t)
        for (std::size_t c = 0; c < 3; ++c) {
            const unsigned a = indices[3 * t + c];
            const unsigned b = indices[3 * t + (c + 1) % 3];
            uses.push_back({(std::uint64_t{std::min(a, b)} << 32) | std::max(a, b), t});
        }
    std::sort(uses.begin(), uses.end(), [](const EdgeUse& x, const EdgeUse& y) { return x.edge < y.edge; });
    std::vector<bool> onBorder(indices.size() / 3, false);
    for (std::size_t i = 0; i < uses.size();) {
        std::size_t j = i + 1;
        while (j < uses.size() && uses[j].edge == uses[i].edge)
            ++j;
        if (j == i + 1)
            onBorder[uses[i].triangle] = true;
        i = j;
    }
    return static_cast<std::size_t>(std::count(onBorder.begin(), onBorder.end(), true));
}

bool isInstance(const BuildNode& node) {
    return node.kind == static_cast<std::uint8_t>(storage::NodeKind::Instance);
}

/** What became of a cell that could have had a stand-in (StandInCounts). */
enum class Outcome : std::uint8_t { None, Kept, NotReducing, TooSmall, TooLarge, NotPaying };

/** A cell's stand-in, if it keeps one, and why (not). */
struct CellChoice {
    std::optional<StandIn> standIn;
    Outcome outcome = Outcome::None;
    SplatOutcome splats = SplatOutcome::Empty;
    /** The measure's counts: splatsNotPaying, errorsRaised, splatsOverSimplified. */
    StandInCounts counts;
};

/**
 * A cell's candidates from `source` of the kinds asked for, and the one it keeps: by measured
 * error and cost (StandInChoice.h), or, with kinds.measured off, its simplified copy where one
 * pays, else its splats.
 */
CellChoice chooseStandIn(
        const BuildNode& node,
        const StandInSource& source,
        const storage::PositionGrid& grid,
        const StandInLimits& limits,
        const StandInKinds& kinds,
        std::uint64_t seed) {
    CellChoice choice;
    std::optional<StandInMeasure> measure;
    if (kinds.measured)
        measure.emplace(source.triangles, node.boundsMin, node.boundsMax);

    std::optional<StandIn> simplified;
    MeasuredStandIn simplifiedMeasured;
    if (kinds.simplified) {
        simplified = simplifySource(source, grid);
        choice.outcome = simplified ? Outcome::Kept : Outcome::NotReducing;
        if (simplified && simplified->triangles.size() > limits.maxTriangles) {
            simplified.reset();
            choice.outcome = Outcome::TooLarge; // its source goes up whole
        }
        if (simplified && measure) {
            simplifiedMeasured = measure->measure(*simplified);
            // Looking worse than it promised, its error is raised, and so is the surface error
            // its parent starts from.
            if (simplifiedMeasured.raised > 0)
                simplified->surfaceError = std::max(simplified->surfaceError, simplifiedMeasured.error);
            simplified->error = simplifiedMeasured.error;
            if (!simplifiedMeasured.pays) {
                simplified.reset();
                choice.outcome = Outcome::NotPaying;
            }
        }
    }

    // Splats where no simplified copy pays; measured, also where they could beat it (their
    // error is at least their source's plus their cover radius).
    const glm::vec3 extent = node.boundsMax - node.boundsMin;
    const float spacing = std::max({extent.x, extent.y, extent.z}) / static_cast<float>(std::max(kinds.splatSpacing, 1));
    const bool trySplats =
            kinds.splatSpacing > 0 &&
            (!simplified ||
             (measure && source.promised() + splatCoverRadius(spacing) < simplified->error * kStandInErrorTie));
    std::optional<StandIn> splatted;
    MeasuredStandIn splatsMeasured;
    bool splatsNotPaying = false;
    if (trySplats) {
        SplatSet splats;
        choice.splats = splatSource(source.triangles, spacing, source.promised(), grid, seed, splats);
        // A point costs about what a triangle does in a page.
        if (choice.splats == SplatOutcome::Kept &&
            splats.points.size() + splats.triangles.size() > limits.maxTriangles)
            choice.splats = SplatOutcome::TooLarge;
        if (choice.splats == SplatOutcome::Kept) {
            splatted.emplace();
            splatted->triangles = std::move(splats.triangles);
            splatted->error = splats.error;
            splatted->kind = StandInKind::Splats;
            splatted->points = std::move(splats.points);
            if (measure) {
                splatsMeasured = measure->measure(*splatted);
                splatted->error = splatsMeasured.error;
                if (!splatsMeasured.pays) {
                    splatted.reset();
                    splatsNotPaying = true;
                    ++choice.counts.splatsNotPaying;
                }
            }
        }
    }

    const bool splatsWin = splatted && simplified && measure &&
                           !measure->firstIsBetter(*simplified, simplifiedMeasured, *splatted, splatsMeasured);
    choice.counts.splatsOverSimplified += splatsWin ? 1u : 0u;
    const MeasuredStandIn& kept = splatsWin || !simplified ? splatsMeasured : simplifiedMeasured;
    if (splatsWin || (splatted && !simplified))
        choice.standIn = std::move(splatted);
    else if (simplified)
        choice.standIn = std::move(simplified);
    if (choice.standIn) {
        choice.outcome = Outcome::Kept;
        choice.counts.errorsRaised += kept.raised > 0 ? 1u : 0u;
    } else if (!kinds.simplified) {
        choice.outcome = splatsNotPaying                             ? Outcome::NotPaying
                         : choice.splats == SplatOutcome::TooLarge ? Outcome::TooLarge
                                                                   : Outcome::NotReducing;
    }
    return choice;
}

} // namespace

std::optional<StandIn> simplifySource(const StandInSource& from, const storage::PositionGrid& grid) {
    const std::span<const storage::PackedTriangle> source = from.triangles;
    if (source.size() < kMinStandInSource)
        return std::nullopt;
    // Weld the corners on the grid, as the encoder will: the simplifier sees the mesh's real
    // topology, and its border is the cell's (a corner shared across cells is one vertex here).
    const std::size_t corners = source.size() * 3;
    std::vector<WeldKey> keys(corners);
    for (std::size_t t = 0; t < source.size(); ++t)
        for (std::size_t c = 0; c < 3; ++c) {
            const storage::PackedVertex& v = source[t].vertices[c];
            keys[3 * t + c] = {grid.quantize(v.position), v.normalOct, v.color};
        }
    std::vector<unsigned> remap(corners);
    const std::size_t unique = meshopt_generateVertexRemap(
            remap.data(), nullptr, corners, keys.data(), corners, sizeof(WeldKey));
    std::vector<WeldKey> welded(unique);
    meshopt_remapVertexBuffer(welded.data(), keys.data(), corners, sizeof(WeldKey), remap.data());
    std::vector<storage::PackedVertex> vertices(unique); // on the grid, as the encoder keeps them
    for (std::size_t v = 0; v < unique; ++v)
        vertices[v] = {grid.position(welded[v].coordinate), welded[v].normalOct, welded[v].color};
    std::vector<unsigned> indices;
    indices.reserve(corners);
    for (std::size_t t = 0; t < source.size(); ++t) {
        const unsigned a = remap[3 * t];
        const unsigned b = remap[3 * t + 1];
        const unsigned c = remap[3 * t + 2];
        if (a != b && b != c && a != c) // collapsed on the grid: the encoder drops it too
            indices.insert(indices.end(), {a, b, c});
    }
    const std::size_t triangles = indices.size() / 3;
    if (triangles < kMinStandInSource)
        return std::nullopt;

    // The border locked: its ring of triangles stays whole, and the rest is simplified towards
    // a share of the source (what the children draw), or towards the most a stand-in may keep
    // where the ring is too large for that (a tree's leaves are all ring: aiming past the
    // limit, the forest kept no simplified copy, its cells kept splats and were drawn 3.7 dB
    // below brute force). No error limit: the stand-in records what it reached, and the
    // runtime draws it only where that error is below ε pixels.
    const auto target = static_cast<std::size_t>(static_cast<double>(source.size()) * kStandInTargetShare);
    const std::size_t ring = borderTriangleCount(indices);
    const auto maxKept = static_cast<std::size_t>(static_cast<double>(source.size()) * kMaxStandInShare);
    float relativeError = 0.0f;
    std::vector<unsigned> kept(indices.size());
    kept.resize(meshopt_simplify(
            kept.data(),
            indices.data(),
            indices.size(),
            vertices[0].position.data(),
            unique,
            sizeof(storage::PackedVertex),
            std::min(std::min(target + ring, maxKept) * 3, indices.size()),
            1.0f,
            meshopt_SimplifyLockBorder,
            &relativeError));
    if (kept.empty() || static_cast<double>(kept.size() / 3) > kMaxStandInShare * static_cast<double>(source.size()))
        return std::nullopt;

    const float scale = meshopt_simplifyScale(vertices[0].position.data(), unique, sizeof(storage::PackedVertex));
    StandIn out;
    out.surfaceError = from.error + relativeError * scale;
    out.shadingError = std::max(from.shadingError, shadingError(vertices, indices, kept));
    out.error = std::max(out.surfaceError, out.shadingError);
    out.triangles.resize(kept.size() / 3);
    for (std::size_t t = 0; t < out.triangles.size(); ++t)
        for (std::size_t c = 0; c < 3; ++c)
            out.triangles[t].vertices[c] = vertices[kept[3 * t + c]];
    return out;
}

Result<ClusterBuildStats> encodeStandIn(
        ClusterEncoder& encoder,
        const StandIn& standIn,
        const storage::PositionGrid& grid,
        std::vector<std::byte>& out) {
    FF_ASSIGN_OR_RETURN(ClusterBuildStats stats, encoder.encodePoints(standIn.points, grid, out));
    if (!standIn.triangles.empty()) {
        FF_ASSIGN_OR_RETURN(const ClusterBuildStats triangles, encoder.encode(standIn.triangles, grid, out));
        stats += triangles;
    }
    return stats;
}

std::size_t maxStandInTriangles(std::uint32_t pageSize) noexcept {
    constexpr std::size_t kPages = 8;
    constexpr std::size_t kBytesPerTriangle = 10; // measured 8.1-8.3 encoded, plus page slack
    return kPages * storage::pagePayloadBytes(pageSize) / kBytesPerTriangle;
}

Result<std::vector<std::optional<StandIn>>> buildStandIns(
        const std::vector<BuildNode>& nodes,
        std::span<const storage::PackedTriangle> triangles,
        const storage::PositionGrid& grid,
        std::span<const PlacedSource> placed,
        unsigned threads,
        StandInSource* rootSource,
        StandInCounts& counts,
        const StandInLimits& limits,
        const StandInKinds& kinds) {
    FF_ASSERT(!nodes.empty());
    std::unordered_map<std::uint32_t, const StandInSource*> placedSources;
    for (const PlacedSource& p : placed)
        placedSources[p.node] = p.source;

    // Nodes by depth from the root, so each level is simplified after the one below it (in parallel
    // within a level: its nodes' sources are disjoint).
    std::vector<std::vector<std::uint32_t>> byDepth(1, {0});
    for (std::size_t d = 0; d < byDepth.size(); ++d) {
        std::vector<std::uint32_t> next;
        for (const std::uint32_t n : byDepth[d]) {
            const BuildNode& node = nodes[n];
            if (node.placedChildren)
                continue;
            for (std::uint32_t c = 0; c < node.childCount; ++c)
                next.push_back(node.firstChild + c);
        }
        if (!next.empty())
            byDepth.push_back(std::move(next));
    }

    std::vector<std::optional<StandIn>> standIns(nodes.size());
    std::vector<StandInSource> sources(nodes.size());
    std::vector<Outcome> outcomes(nodes.size(), Outcome::None);
    std::vector<SplatOutcome> splatOutcomes(nodes.size(), SplatOutcome::Empty);
    std::vector<StandInCounts> measuredCounts(nodes.size());
    std::vector<float> largestBelow(nodes.size(), 0.0f); // the largest stand-in error in each subtree
    for (std::size_t d = byDepth.size(); d-- > 0;) {
        const std::vector<std::uint32_t>& level = byDepth[d];
        FF_RETURN_IF_ERROR(parallelFor(level.size(), threads, [&] {
            return [&](std::size_t k) -> Status {
                const std::uint32_t n = level[k];
                const BuildNode& node = nodes[n];
                StandInSource& source = sources[n];
                if (isInstance(node)) {
                    source.usable = false;
                    return Status::ok();
                }
                if (node.placedChildren || node.placedTriangles) {
                    const auto p = placedSources.find(n);
                    if (p == placedSources.end() || p->second == nullptr)
                        source.usable = false;
                    else
                        source = *p->second;
                    return Status::ok();
                }
                std::size_t size = node.triangleCount;
                for (std::uint32_t c = 0; c < node.childCount; ++c)
                    largestBelow[n] = std::max(largestBelow[n], largestBelow[node.firstChild + c]);
                for (std::uint32_t c = 0; c < node.childCount; ++c) {
                    const StandInSource& child = sources[node.firstChild + c];
                    source.usable = source.usable && child.usable;
                    size += child.triangles.size();
                    source.error = std::max(source.error, child.error);
                    source.shadingError = std::max(source.shadingError, child.shadingError);
                }
                if (!source.usable || size > kMaxStandInSource) {
                    source = StandInSource::unusable();
                    outcomes[n] = Outcome::TooLarge;
                    return Status::ok();
                }
                source.triangles.reserve(size);
                const auto own = triangles.subspan(node.firstTriangle, node.triangleCount);
                source.triangles.insert(source.triangles.end(), own.begin(), own.end());
                for (std::uint32_t c = 0; c < node.childCount; ++c) {
                    const StandInSource& child = sources[node.firstChild + c];
                    source.triangles.insert(
                            source.triangles.end(), child.triangles.begin(), child.triangles.end());
                }
                // A leaf below the root is left to its parent, which simplifies it from its
                // own triangles rather than from a simplification of them: errors add up a
                // level less (on the 4 M terrain at 6 radii 103 k triangles drawn against 234 k
                // with leaf stand-ins, as accurate) and a quarter of the nodes carry one.
                const bool leafBelowRoot = node.childCount == 0 && (n != 0 || !limits.rootIsTop);
                if (source.triangles.size() < kMinStandInSource || leafBelowRoot) {
                    outcomes[n] = Outcome::TooSmall;
                    return Status::ok();
                }
                CellChoice choice = chooseStandIn(node, source, grid, limits, kinds, 0x5eed0000ull + n);
                outcomes[n] = choice.outcome;
                splatOutcomes[n] = choice.splats;
                measuredCounts[n] = choice.counts;
                if (choice.standIn) {
                    // Never below a stand-in under it (a child's splats add their cover radius
                    // to the source they share with this cell).
                    choice.standIn->error = std::max(choice.standIn->error, largestBelow[n]);
                    largestBelow[n] = choice.standIn->error;
                    standIns[n] = std::move(choice.standIn);
                    if (standIns[n]->kind == StandInKind::Simplified) {
                        // Its parent simplifies what it keeps, from its errors.
                        source.triangles = standIns[n]->triangles;
                        source.error = standIns[n]->surfaceError;
                        source.shadingError = standIns[n]->shadingError;
                    }
                }
                return Status::ok(); // the parent splats or simplifies this source whole
            };
        }));
        // The level below has been simplified into this one: its sources are spent.
        if (d + 1 < byDepth.size())
            for (const std::uint32_t n : byDepth[d + 1])
                sources[n] = StandInSource{};
    }
    if (rootSource != nullptr)
        *rootSource = std::move(sources[0]);
    for (std::size_t n = 0; n < nodes.size(); ++n) {
        counts.splats += standIns[n] && standIns[n]->kind == StandInKind::Splats ? 1u : 0u;
        counts.splatsNotReducing += splatOutcomes[n] == SplatOutcome::NotReducing ? 1u : 0u;
        counts.splatsTooLarge += splatOutcomes[n] == SplatOutcome::TooLarge ? 1u : 0u;
    }
    for (const StandInCounts& measured : measuredCounts)
        counts += measured;
    for (const Outcome outcome : outcomes) {
        counts.kept += outcome == Outcome::Kept ? 1 : 0;
        counts.notReducing += outcome == Outcome::NotReducing ? 1 : 0;
        counts.tooSmall += outcome == Outcome::TooSmall ? 1 : 0;
        counts.tooLarge += outcome == Outcome::TooLarge ? 1 : 0;
        counts.notPaying += outcome == Outcome::NotPaying ? 1 : 0;
    }
    return standIns;
}

} // namespace ff::builder
