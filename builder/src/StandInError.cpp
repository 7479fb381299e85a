#include "StandInError.h"

#include <ff/storage/VertexCodec.h>

#include <glm/glm.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <unordered_map>
#include <utility>
#include <vector>

namespace ff::builder {

namespace {

glm::vec3 positionOf(const storage::PackedVertex& v) {
    return {v.position[0], v.position[1], v.position[2]};
}

/** The point of triangle abc nearest p, as barycentric weights of a, b, c (by the regions of
 *  the triangle's plane: a corner, an edge, or the inside). */
glm::vec3 nearestBarycentric(const glm::vec3& p, const glm::vec3& a, const glm::vec3& b, const glm::vec3& c) {
    const glm::vec3 ab = b - a;
    const glm::vec3 ac = c - a;
    const glm::vec3 ap = p - a;
    const float d1 = glm::dot(ab, ap);
    const float d2 = glm::dot(ac, ap);
    if (d1 <= 0.0f && d2 <= 0.0f)
        return {1, 0, 0};
    const glm::vec3 bp = p - b;
    const float d3 = glm::dot(ab, bp);
    const float d4 = glm::dot(ac, bp);
    if (d3 >= 0.0f && d4 <= d3)
        return {0, 1, 0};
    const float vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0f && d1 >= 0.0f && d3 <= 0.0f) {
        const float t = d1 / (d1 - d3);
        return {1 - t, t, 0};
    }
    const glm::vec3 cp = p - c;
    const float d5 = glm::dot(ab, cp);
    const float d6 = glm::dot(ac, cp);
    if (d6 >= 0.0f && d5 <= d6)
        return {0, 0, 1};
    const float vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0f && d2 >= 0.0f && d6 <= 0.0f) {
        const float t = d2 / (d2 - d6);
        return {1 - t, 0, t};
    }
    const float va = d3 * d6 - d5 * d4;
    if (va <= 0.0f && (d4 - d3) >= 0.0f && (d5 - d6) >= 0.0f) {
        const float t = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return {0, 1 - t, t};
    }
    const float sum = va + vb + vc;
    if (!(sum > 0.0f)) // a degenerate triangle: its first corner
        return {1, 0, 0};
    return {va / sum, vb / sum, vc / sum};
}

/** The stand-in's triangles binned by their bounds in a uniform grid. */
class TriangleGrid {
public:
    TriangleGrid(std::span<const storage::PackedVertex> vertices, std::span<const unsigned> kept, float cell)
        : mVertices(vertices)
        , mKept(kept)
        , mCell(cell) {
        // A triangle is binned in every cell its bounds touch: large ones in a fine grid would
        // take unbounded memory, so the cells grow until the entries are at most
        // kEntriesPerTriangle a triangle on average.
        const std::size_t triangles = kept.size() / 3;
        while (entries() > kEntriesPerTriangle * triangles)
            mCell *= 2.0f;
        for (std::size_t t = 0; t < triangles; ++t) {
            const auto [from, to] = cellRange(t);
            for (std::int64_t x = from[0]; x <= to[0]; ++x)
                for (std::int64_t y = from[1]; y <= to[1]; ++y)
                    for (std::int64_t z = from[2]; z <= to[2]; ++z)
                        mCells[key({x, y, z})].push_back(static_cast<std::uint32_t>(t));
        }
    }

    struct Nearest {
        std::uint32_t triangle = 0;
        glm::vec3 weights{1, 0, 0};
        float distance = INFINITY;
    };

    /** The triangle nearest `p`, searched ring by ring of cells until none can be nearer. */
    Nearest nearest(const glm::vec3& p) const {
        Nearest best;
        const std::array<std::int64_t, 3> centre = cellOf(p);
        for (std::int64_t r = 0; r <= kMaxRings; ++r) {
            for (std::int64_t dx = -r; dx <= r; ++dx)
                for (std::int64_t dy = -r; dy <= r; ++dy)
                    for (std::int64_t dz = -r; dz <= r; ++dz) {
                        if (std::max({std::abs(dx), std::abs(dy), std::abs(dz)}) != r)
                            continue; // inner rings were searched
                        const auto found = mCells.find(key({centre[0] + dx, centre[1] + dy, centre[2] + dz}));
                        if (found == mCells.end())
                            continue;
                        for (const std::uint32_t t : found->second) {
                            const glm::vec3 w = nearestBarycentric(p, corner(t, 0), corner(t, 1), corner(t, 2));
                            const glm::vec3 q = w.x * corner(t, 0) + w.y * corner(t, 1) + w.z * corner(t, 2);
                            const float d = glm::length(p - q);
                            if (d < best.distance)
                                best = {t, w, d};
                        }
                    }
            // A triangle binned only in ring r + 1 or beyond is at least r cells away.
            if (best.distance <= static_cast<float>(r) * mCell)
                return best;
        }
        return Nearest{}; // not found for sure within the rings searched
    }

    [[nodiscard]] const storage::PackedVertex& vertex(std::uint32_t triangle, int c) const {
        return mVertices[mKept[3 * triangle + static_cast<std::size_t>(c)]];
    }
    [[nodiscard]] glm::vec3 corner(std::size_t triangle, int c) const {
        return positionOf(mVertices[mKept[3 * triangle + static_cast<std::size_t>(c)]]);
    }

    /** Rings searched at most: a removed vertex lies within a ring or two of a kept triangle
     *  on a surface; past this nearest() reports none (the caller counts that as the worst). */
    static constexpr std::int64_t kMaxRings = 16;

private:
    static constexpr std::size_t kEntriesPerTriangle = 16;

    std::pair<std::array<std::int64_t, 3>, std::array<std::int64_t, 3>> cellRange(std::size_t t) const {
        glm::vec3 lo = corner(t, 0);
        glm::vec3 hi = lo;
        for (int c = 1; c < 3; ++c) {
            lo = glm::min(lo, corner(t, c));
            hi = glm::max(hi, corner(t, c));
        }
        return {cellOf(lo), cellOf(hi)};
    }
    /** Cell entries binning every triangle at the current cell size would take. */
    std::size_t entries() const {
        std::size_t total = 0;
        for (std::size_t t = 0; t < mKept.size() / 3; ++t) {
            const auto [from, to] = cellRange(t);
            std::size_t cells = 1;
            for (std::size_t a = 0; a < 3; ++a)
                cells *= static_cast<std::size_t>(to[a] - from[a] + 1);
            total += cells;
        }
        return total;
    }

    std::array<std::int64_t, 3> cellOf(const glm::vec3& p) const {
        return {static_cast<std::int64_t>(std::floor(p.x / mCell)),
                static_cast<std::int64_t>(std::floor(p.y / mCell)),
                static_cast<std::int64_t>(std::floor(p.z / mCell))};
    }
    static std::uint64_t key(const std::array<std::int64_t, 3>& c) {
        const auto bits = [](std::int64_t x) { return static_cast<std::uint64_t>(x) & 0x1FFFFFu; };
        return bits(c[0]) << 42 | bits(c[1]) << 21 | bits(c[2]);
    }

    std::span<const storage::PackedVertex> mVertices;
    std::span<const unsigned> mKept;
    float mCell;
    std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> mCells;
};

/** What triangle `t` of `grid` interpolates at barycentric `w`: colour per channel, the normal
 *  renormalised (unlit where a corner is). */
storage::PackedVertex interpolate(const TriangleGrid& grid, std::uint32_t t, const glm::vec3& w) {
    storage::PackedVertex out = grid.vertex(t, 0);
    glm::vec3 normal(0.0f);
    bool unlit = false;
    for (std::size_t ch = 0; ch < 4; ++ch) {
        float value = 0.0f;
        for (int c = 0; c < 3; ++c)
            value += w[c] * static_cast<float>(grid.vertex(t, c).color[ch]);
        out.color[ch] = static_cast<std::uint8_t>(std::clamp(std::lround(value), 0l, 255l));
    }
    for (int c = 0; c < 3; ++c) {
        const storage::PackedVertex& v = grid.vertex(t, c);
        unlit = unlit || storage::isUnlitNormal(v.normalOct);
        const std::array<float, 3> n = storage::decodeOctNormal(v.normalOct);
        normal += w[c] * glm::vec3(n[0], n[1], n[2]);
    }
    const float length = glm::length(normal);
    out.normalOct = unlit ? storage::kUnlitNormalOct
                          : length > 0.0f ? storage::encodeOctNormal(normal.x / length, normal.y / length, normal.z / length)
                                          : out.normalOct;
    return out;
}

} // namespace

float shadingDifference(const storage::PackedVertex& a, const storage::PackedVertex& b) {
    if (storage::isUnlitNormal(a.normalOct) != storage::isUnlitNormal(b.normalOct))
        return 1.0f;
    int colour = 0;
    for (std::size_t c = 0; c < 4; ++c)
        colour = std::max(colour, std::abs(int{a.color[c]} - int{b.color[c]}));
    float difference = static_cast<float>(colour) / kShadingColourStep;
    if (!storage::isUnlitNormal(a.normalOct)) {
        const std::array<float, 3> na = storage::decodeOctNormal(a.normalOct);
        const std::array<float, 3> nb = storage::decodeOctNormal(b.normalOct);
        const float cosine = std::clamp(na[0] * nb[0] + na[1] * nb[1] + na[2] * nb[2], -1.0f, 1.0f);
        const float step = kShadingNormalStepDegrees * 3.14159265f / 180.0f;
        difference = std::max(difference, std::acos(cosine) / step);
    }
    return std::min(difference, 1.0f);
}

float shadingError(
        std::span<const storage::PackedVertex> vertices,
        std::span<const unsigned> source,
        std::span<const unsigned> kept) {
    if (kept.size() < 3)
        return 0.0f;
    std::vector<bool> inKept(vertices.size(), false);
    glm::vec3 lo(INFINITY);
    glm::vec3 hi(-INFINITY);
    for (const unsigned v : kept) {
        inKept[v] = true;
        lo = glm::min(lo, positionOf(vertices[v]));
        hi = glm::max(hi, positionOf(vertices[v]));
    }
    const glm::vec3 size = hi - lo;
    const float extent = std::max({size.x, size.y, size.z});
    if (!(extent > 0.0f))
        return 0.0f; // every kept corner on one point: nothing is drawn
    // Cells about the stand-in's triangle spacing on a surface.
    const float cell = extent / std::sqrt(static_cast<float>(kept.size() / 3));
    const TriangleGrid grid(vertices, kept, cell);
    std::vector<bool> done(vertices.size(), false);
    float most = 0.0f;
    for (const unsigned v : source) {
        if (inKept[v] || done[v])
            continue;
        done[v] = true;
        const glm::vec3 p = positionOf(vertices[v]);
        const TriangleGrid::Nearest at = grid.nearest(p);
        if (!std::isfinite(at.distance)) {
            most = std::max(most, extent); // far from every kept triangle: assume the worst
            continue;
        }
        const float difference = shadingDifference(vertices[v], interpolate(grid, at.triangle, at.weights));
        if (!(difference > 0.0f))
            continue;
        float spacing = INFINITY; // to the nearest corner: how far its shading can drift
        for (int c = 0; c < 3; ++c)
            spacing = std::min(spacing, glm::length(p - grid.corner(at.triangle, c)));
        most = std::max(most, difference * spacing);
    }
    return most;
}

} // namespace ff::builder
