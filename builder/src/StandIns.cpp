#include "StandIns.h"

#include "ParallelFor.h"
#include "Splats.h"
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

bool isInstance(const BuildNode& node) {
    return node.kind == static_cast<std::uint8_t>(storage::NodeKind::Instance);
}

} // namespace

std::optional<StandIn> simplifySource(
        std::span<const storage::PackedTriangle> source,
        float baseError,
        const storage::PositionGrid& grid) {
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

    const auto target = static_cast<std::size_t>(static_cast<double>(triangles) * kStandInTargetShare) * 3;
    std::vector<unsigned> kept(indices.size());
    float relativeError = 0.0f;
    // No error limit: the stand-in records what it reached, and the runtime draws it only from
    // where that error is below ε pixels.
    const std::size_t keptIndices = meshopt_simplify(
            kept.data(),
            indices.data(),
            indices.size(),
            vertices[0].position.data(),
            unique,
            sizeof(storage::PackedVertex),
            target,
            1.0f,
            meshopt_SimplifyLockBorder,
            &relativeError);
    if (keptIndices == 0 ||
        static_cast<double>(keptIndices / 3) > kMaxStandInShare * static_cast<double>(triangles))
        return std::nullopt;

    kept.resize(keptIndices);
    const float scale = meshopt_simplifyScale(vertices[0].position.data(), unique, sizeof(storage::PackedVertex));
    StandIn out;
    out.error = baseError + std::max(relativeError * scale, shadingError(vertices, indices, kept));
    out.triangles.resize(keptIndices / 3);
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
    enum class Outcome : std::uint8_t { None, Kept, NotReducing, TooSmall, TooLarge };
    std::vector<Outcome> outcomes(nodes.size(), Outcome::None);
    std::vector<SplatOutcome> splatOutcomes(nodes.size(), SplatOutcome::Empty);
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
                for (std::uint32_t c = 0; c < node.childCount; ++c) {
                    const StandInSource& child = sources[node.firstChild + c];
                    source.usable = source.usable && child.usable;
                    size += child.triangles.size();
                    source.error = std::max(source.error, child.error);
                }
                if (!source.usable || size > kMaxStandInSource) {
                    source = StandInSource{{}, 0.0f, false};
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
                if (kinds.simplified) {
                    standIns[n] = simplifySource(source.triangles, source.error, grid);
                    outcomes[n] = standIns[n] ? Outcome::Kept : Outcome::NotReducing;
                    if (standIns[n] && standIns[n]->triangles.size() > limits.maxTriangles) {
                        standIns[n].reset();
                        outcomes[n] = Outcome::TooLarge; // its source goes up whole
                    }
                    if (standIns[n]) {
                        source.triangles = standIns[n]->triangles;
                        source.error = standIns[n]->error;
                        return Status::ok();
                    }
                }
                if (kinds.splatSpacing > 0) {
                    const glm::vec3 extent = node.boundsMax - node.boundsMin;
                    const float spacing =
                            std::max({extent.x, extent.y, extent.z}) / static_cast<float>(kinds.splatSpacing);
                    SplatSet splats;
                    splatOutcomes[n] =
                            splatSource(source.triangles, spacing, source.error, grid, 0x5eed0000ull + n, splats);
                    // A point costs about what a triangle does in a page.
                    if (splatOutcomes[n] == SplatOutcome::Kept &&
                        splats.points.size() + splats.triangles.size() > limits.maxTriangles)
                        splatOutcomes[n] = SplatOutcome::TooLarge;
                    if (splatOutcomes[n] == SplatOutcome::Kept) {
                        standIns[n] = StandIn{
                                std::move(splats.triangles), splats.error, StandInKind::Splats,
                                std::move(splats.points)};
                        outcomes[n] = Outcome::Kept;
                    } else if (!kinds.simplified) {
                        outcomes[n] = splatOutcomes[n] == SplatOutcome::TooLarge ? Outcome::TooLarge
                                                                                 : Outcome::NotReducing;
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
    for (const Outcome outcome : outcomes) {
        counts.kept += outcome == Outcome::Kept ? 1 : 0;
        counts.notReducing += outcome == Outcome::NotReducing ? 1 : 0;
        counts.tooSmall += outcome == Outcome::TooSmall ? 1 : 0;
        counts.tooLarge += outcome == Outcome::TooLarge ? 1 : 0;
    }
    return standIns;
}

} // namespace ff::builder
