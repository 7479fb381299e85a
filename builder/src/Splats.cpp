#include "Splats.h"

#include <ff/storage/Assert.h>
#include <ff/storage/VertexCodec.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <optional>
#include <random>
#include <unordered_set>

namespace ff::builder {

namespace {

using Vec3 = std::array<float, 3>;

Vec3 sub(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
float dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
Vec3 cross(const Vec3& a, const Vec3& b) {
    return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
float distanceSquared(const Vec3& a, const Vec3& b) {
    const Vec3 d = sub(a, b);
    return dot(d, d);
}

double areaOf(const storage::PackedTriangle& t) {
    const Vec3 n = cross(
            sub(t.vertices[1].position, t.vertices[0].position),
            sub(t.vertices[2].position, t.vertices[0].position));
    const double a = 0.5 * std::sqrt(static_cast<double>(dot(n, n)));
    return std::isfinite(a) ? a : 0.0;
}

/**
 * Points binned on a grid of cubes of half the query radius, for "every point within r"
 * queries: a counting sort into a dense table of cubes, at most 64 an axis (a cell splatted at
 * 1/N of its side spans 4 N such cubes; beyond N = 16 they grow and queries scan more points).
 */
class PointGrid {
public:
    PointGrid(std::span<const Vec3> points, float radius) : mPoints(points) {
        Vec3 hi{-INFINITY, -INFINITY, -INFINITY};
        mOrigin = {INFINITY, INFINITY, INFINITY};
        for (const Vec3& p : points)
            for (std::size_t a = 0; a < 3; ++a) {
                mOrigin[a] = std::min(mOrigin[a], p[a]);
                hi[a] = std::max(hi[a], p[a]);
            }
        float extent = 0.0f;
        for (std::size_t a = 0; a < 3; ++a)
            extent = std::max(extent, points.empty() ? 0.0f : hi[a] - mOrigin[a]);
        // Cubes of half the radius: a query scans 5^3 of them, 1.7 x fewer points than 3^3 cubes
        // of the radius where points fill a volume (foliage).
        mCell = std::max({radius / 2.0f, extent / static_cast<float>(kMaxCells - 1), 1e-30f});
        for (std::size_t a = 0; a < 3; ++a) {
            const float cubes = (hi[a] - mOrigin[a]) / mCell; // NaN where points are not finite
            mSize[a] = cubes >= 0.0f ? std::min(kMaxCells, static_cast<std::int64_t>(std::min(cubes, 1e9f)) + 1) : 1;
        }
        mFirst.assign(static_cast<std::size_t>(mSize[0] * mSize[1] * mSize[2]) + 1, 0);
        std::vector<std::uint32_t> cellOfPoint(points.size());
        for (std::size_t i = 0; i < points.size(); ++i) {
            cellOfPoint[i] = indexOf(cellOf(points[i]));
            ++mFirst[cellOfPoint[i] + 1];
        }
        for (std::size_t c = 1; c < mFirst.size(); ++c)
            mFirst[c] += mFirst[c - 1];
        mSorted.resize(points.size());
        std::vector<std::uint32_t> next(mFirst.begin(), mFirst.end() - 1);
        for (std::uint32_t i = 0; i < points.size(); ++i)
            mSorted[next[cellOfPoint[i]]++] = i;
    }

    template <typename Visit>
    void forEachWithin(const Vec3& p, float radius, Visit&& visit) const {
        const std::array<std::int64_t, 3> c = cellOf(p);
        const float r2 = radius * radius;
        // Cubes each way that hold every point within the radius (NaN radius: one).
        const auto r = static_cast<std::int64_t>(std::ceil(std::clamp(radius / mCell, 1.0f, static_cast<float>(kMaxCells))));
        for (std::int64_t z = std::max<std::int64_t>(c[2] - r, 0); z <= std::min(c[2] + r, mSize[2] - 1); ++z)
            for (std::int64_t y = std::max<std::int64_t>(c[1] - r, 0); y <= std::min(c[1] + r, mSize[1] - 1); ++y)
                for (std::int64_t x = std::max<std::int64_t>(c[0] - r, 0); x <= std::min(c[0] + r, mSize[0] - 1); ++x) {
                    const std::uint32_t cell = indexOf({x, y, z});
                    for (std::uint32_t k = mFirst[cell]; k < mFirst[cell + 1]; ++k)
                        if (distanceSquared(mPoints[mSorted[k]], p) <= r2)
                            visit(mSorted[k]);
                }
    }

private:
    static constexpr std::int64_t kMaxCells = 64;

    std::array<std::int64_t, 3> cellOf(const Vec3& p) const {
        std::array<std::int64_t, 3> c{};
        for (std::size_t a = 0; a < 3; ++a) {
            const float at = std::floor((p[a] - mOrigin[a]) / mCell); // NaN: cube 0
            c[a] = at >= 0.0f ? std::min(static_cast<std::int64_t>(std::min(at, 1e9f)), mSize[a] - 1) : 0;
        }
        return c;
    }
    std::uint32_t indexOf(const std::array<std::int64_t, 3>& c) const {
        return static_cast<std::uint32_t>((c[2] * mSize[1] + c[1]) * mSize[0] + c[0]);
    }

    std::span<const Vec3> mPoints;
    float mCell = 1.0f;
    Vec3 mOrigin{};
    std::array<std::int64_t, 3> mSize{1, 1, 1};
    std::vector<std::uint32_t> mFirst;  ///< per cube, where its points start in mSorted
    std::vector<std::uint32_t> mSorted; ///< point indices by cube
};

/** A candidate: a random point of triangle `triangle` (an index into the source). */
struct Candidate {
    Vec3 position;
    std::uint32_t triangle;
    float b1, b2; ///< barycentric weights of corners 1 and 2
};

/** Shading attributes of a surface point: linear colour, alpha, a unit normal or unlit. */
struct Attributes {
    Vec3 linear{};
    float alpha = 1.0f;
    Vec3 normal{0.0f, 0.0f, 1.0f};
    bool unlit = false;
};

Attributes attributesOf(const Candidate& c, std::span<const storage::PackedTriangle> source) {
    const storage::PackedTriangle& t = source[c.triangle];
    const float w[3] = {1.0f - c.b1 - c.b2, c.b1, c.b2};
    Attributes a;
    a.alpha = 0.0f;
    Vec3 n{};
    for (std::size_t k = 0; k < 3; ++k) {
        const storage::PackedVertex& v = t.vertices[k];
        a.unlit = a.unlit || storage::isUnlitNormal(v.normalOct);
        const Vec3 vn = storage::decodeOctNormal(v.normalOct);
        for (std::size_t i = 0; i < 3; ++i) {
            a.linear[i] += w[k] * storage::srgb8ToLinear(v.color[i]);
            n[i] += w[k] * vn[i];
        }
        a.alpha += w[k] * static_cast<float>(v.color[3]) / 255.0f;
    }
    const float length = std::sqrt(dot(n, n));
    if (length > 1e-6f)
        a.normal = {n[0] / length, n[1] / length, n[2] / length};
    return a;
}

struct Sampled {
    std::vector<Candidate> survivors; ///< one per candidate bin, in random order
    std::vector<std::uint32_t> kept;  ///< stratified: indices into survivors
};

/**
 * Candidates on the triangles `eligible` (indices into `source`) at `spacing`, thinned to one a
 * bin, then stratified. nullopt when more than kMaxSplatBins would be needed.
 */
std::optional<Sampled> sample(
        std::span<const storage::PackedTriangle> source,
        std::span<const std::uint32_t> eligible,
        std::span<const double> areas,
        float spacing,
        std::mt19937_64& random) {
    std::vector<double> cumulative(eligible.size());
    double total = 0.0;
    for (std::size_t i = 0; i < eligible.size(); ++i)
        cumulative[i] = total += areas[eligible[i]];
    // Bins of diagonal spacing/8: a surface covering one fully has at least its side squared of
    // area in it, so there are at most total / side^2 such bins to fill.
    const double side = spacing / 8.0 / std::sqrt(3.0);
    const double bins = std::max(1.0, std::ceil(total / (side * side)));
    const double wanted = std::ceil(kSplatSafety * bins * std::log(std::max(bins, 2.0)));
    if (!(bins <= static_cast<double>(kMaxSplatBins)))
        return std::nullopt;
    const auto count = static_cast<std::size_t>(wanted);

    // The bins span the triangles' bounds; candidates are drawn one at a time and only the
    // first a bin keeps (the draw order is random), so memory follows the bins, not the draws.
    Vec3 lo{INFINITY, INFINITY, INFINITY};
    Vec3 hi{-INFINITY, -INFINITY, -INFINITY};
    for (const std::uint32_t t : eligible)
        for (const storage::PackedVertex& v : source[t].vertices)
            for (std::size_t a = 0; a < 3; ++a) {
                lo[a] = std::min(lo[a], v.position[a]);
                hi[a] = std::max(hi[a], v.position[a]);
            }
    std::array<std::uint64_t, 3> size{};
    for (std::size_t a = 0; a < 3; ++a)
        size[a] = static_cast<std::uint64_t>(std::floor((static_cast<double>(hi[a]) - lo[a]) / side)) + 1;
    const auto binOf = [&](const Vec3& p) {
        std::array<std::uint64_t, 3> b{};
        for (std::size_t a = 0; a < 3; ++a)
            b[a] = std::min(
                    size[a] - 1,
                    static_cast<std::uint64_t>(std::max(0.0, std::floor((static_cast<double>(p[a]) - lo[a]) / side))));
        return (b[2] * size[1] + b[1]) * size[0] + b[0]; // < 2^64: a cell spans < 2^21 bins a side
    };
    constexpr std::uint64_t kMaxDenseBins = std::uint64_t{1} << 27; // a 16 MiB bit table
    const bool dense = size[0] * size[1] * size[2] <= kMaxDenseBins;
    std::vector<bool> taken(dense ? size[0] * size[1] * size[2] : 0, false);
    std::unordered_set<std::uint64_t> takenSparse;

    Sampled out;
    const auto keepFirstInItsBin = [&](const Candidate& c) {
        const std::uint64_t bin = binOf(c.position);
        if (dense ? taken[bin] : !takenSparse.insert(bin).second)
            return;
        if (dense)
            taken[bin] = true;
        out.survivors.push_back(c);
    };
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    for (std::size_t k = 0; k < count; ++k) {
        Candidate c;
        const double at = unit(random) * total;
        const auto found = std::upper_bound(cumulative.begin(), cumulative.end(), at);
        const std::uint32_t t =
                eligible[static_cast<std::size_t>(std::min<std::ptrdiff_t>(found - cumulative.begin(),
                                                                            static_cast<std::ptrdiff_t>(eligible.size()) - 1))];
        // Uniform on the triangle: sqrt of one uniform picks the distance from corner 0.
        const float r1 = std::sqrt(static_cast<float>(unit(random)));
        const float r2 = static_cast<float>(unit(random));
        c.triangle = t;
        c.b1 = r1 * (1.0f - r2);
        c.b2 = r1 * r2;
        const auto& v = source[t].vertices;
        for (std::size_t a = 0; a < 3; ++a)
            c.position[a] = (1.0f - c.b1 - c.b2) * v[0].position[a] + c.b1 * v[1].position[a] +
                            c.b2 * v[2].position[a];
        keepFirstInItsBin(c);
    }
    // Every edge too, at most a bin's side apart: a bin the surface crosses without covering it
    // fully holds an edge (a plane's section of a cube has at least a face's area), which the
    // draws by area need not reach (a wire, a leaf's rim).
    for (const std::uint32_t t : eligible) {
        const auto& v = source[t].vertices;
        for (std::size_t e = 0; e < 3; ++e) {
            const Vec3 from = v[e].position;
            const Vec3 to = v[(e + 1) % 3].position;
            const double length = std::sqrt(static_cast<double>(distanceSquared(from, to)));
            const auto steps = static_cast<std::uint32_t>(std::max(1.0, std::ceil(length / side)));
            for (std::uint32_t k = 0; k < steps; ++k) {
                const float at = static_cast<float>(k) / static_cast<float>(steps);
                // Barycentric weights of corners 1 and 2 at `at` along edge e.
                const std::array<std::array<float, 2>, 3> weights = {
                        {{at, 0.0f}, {1.0f - at, at}, {0.0f, 1.0f - at}}};
                Candidate c;
                c.triangle = t;
                c.b1 = weights[e][0];
                c.b2 = weights[e][1];
                for (std::size_t a = 0; a < 3; ++a)
                    c.position[a] = from[a] + at * (to[a] - from[a]);
                keepFirstInItsBin(c);
            }
        }
        if (out.survivors.size() > 2 * kMaxSplatBins)
            return std::nullopt; // thin geometry: far more bins crossed than its area fills
    }
    // Stratified in a random order (edge samples were kept in triangle order).
    std::shuffle(out.survivors.begin(), out.survivors.end(), random);

    std::vector<Vec3> positions(out.survivors.size());
    for (std::size_t i = 0; i < positions.size(); ++i)
        positions[i] = out.survivors[i].position;
    std::vector<std::uint32_t> order(positions.size());
    std::iota(order.begin(), order.end(), 0u); // survivors are shuffled
    out.kept = stratify(positions, order, spacing / 2.0f);
    return out;
}

/** A kept point's attributes: a Gaussian average of the survivors around it (σ = radius / 2),
 *  normals turned to its own side first (shading is two-sided), lit and unlit kept apart. */
storage::PackedVertex filtered(
        std::uint32_t point,
        const Sampled& sampled,
        std::span<const Attributes> attributes,
        const PointGrid& grid,
        float radius,
        const storage::PositionGrid& positionGrid) {
    const Attributes& own = attributes[point];
    const float inverse2Sigma2 = 1.0f / (2.0f * (radius / 2.0f) * (radius / 2.0f));
    const Vec3& centre = sampled.survivors[point].position;
    Vec3 linear{};
    Vec3 normal{};
    float alpha = 0.0f;
    float weights = 0.0f;
    grid.forEachWithin(centre, radius, [&](std::uint32_t j) {
        const Attributes& other = attributes[j];
        if (other.unlit != own.unlit)
            return;
        const float w = std::exp(-distanceSquared(sampled.survivors[j].position, centre) * inverse2Sigma2);
        const float side = dot(other.normal, own.normal) < 0.0f ? -1.0f : 1.0f;
        for (std::size_t a = 0; a < 3; ++a) {
            linear[a] += w * other.linear[a];
            normal[a] += w * side * other.normal[a];
        }
        alpha += w * other.alpha;
        weights += w;
    });
    FF_ASSERT(weights > 0.0f); // the point itself is within the radius
    storage::PackedVertex v;
    v.position = positionGrid.position(positionGrid.quantize(centre));
    const float length = std::sqrt(dot(normal, normal));
    v.normalOct = own.unlit ? storage::kUnlitNormalOct
                            : (length > 1e-6f ? storage::encodeOctNormal(normal[0], normal[1], normal[2])
                                              : storage::encodeOctNormal(own.normal[0], own.normal[1], own.normal[2]));
    for (std::size_t a = 0; a < 3; ++a)
        v.color[a] = storage::linearToSrgb8(linear[a] / weights);
    v.color[3] = storage::toUnorm8(alpha / weights);
    return v;
}

} // namespace

std::vector<std::uint32_t> stratify(
        std::span<const std::array<float, 3>> points,
        std::span<const std::uint32_t> order,
        float radius) {
    FF_ASSERT(order.size() == points.size());
    const PointGrid grid(points, radius);
    // covers[i]: neighbours of i within the radius not deleted. A point may go when something
    // else still covers it and every deleted neighbour keeps another cover without it. Found
    // again when needed rather than stored: a volume of foliage has thousands a point.
    std::vector<std::uint32_t> covers(points.size(), 0);
    for (std::uint32_t i = 0; i < points.size(); ++i)
        grid.forEachWithin(points[i], radius, [&](std::uint32_t j) { covers[i] += j != i ? 1u : 0u; });
    std::vector<bool> deleted(points.size(), false);
    std::vector<std::uint32_t> neighbours;
    for (const std::uint32_t p : order) {
        if (covers[p] == 0)
            continue;
        neighbours.clear();
        bool onlyCover = false;
        grid.forEachWithin(points[p], radius, [&](std::uint32_t j) {
            if (j == p)
                return;
            neighbours.push_back(j);
            onlyCover = onlyCover || (deleted[j] && covers[j] < 2);
        });
        if (onlyCover)
            continue;
        deleted[p] = true;
        for (const std::uint32_t j : neighbours)
            --covers[j];
    }
    std::vector<std::uint32_t> kept;
    for (std::uint32_t i = 0; i < points.size(); ++i)
        if (!deleted[i])
            kept.push_back(i);
    return kept;
}

SplatOutcome splatSource(
        std::span<const storage::PackedTriangle> source,
        float spacing,
        float baseError,
        const storage::PositionGrid& grid,
        std::uint64_t seed,
        SplatSet& out) {
    std::vector<double> areas(source.size());
    std::vector<std::uint32_t> eligible;
    for (std::uint32_t t = 0; t < source.size(); ++t) {
        areas[t] = areaOf(source[t]);
        if (areas[t] > 0.0)
            eligible.push_back(t);
    }
    if (eligible.empty() || !(spacing > 0.0f) || !std::isfinite(spacing))
        return SplatOutcome::Empty;

    std::mt19937_64 random(seed);
    std::optional<Sampled> sampled = sample(source, eligible, areas, spacing, random);
    // Triangles large enough to keep several splats are cheaper drawn as they are: keep them,
    // and splat the rest again (their splats covered the kept triangles' neighbours too).
    std::vector<std::uint32_t> perTriangle(source.size(), 0);
    if (sampled)
        for (const std::uint32_t k : sampled->kept)
            ++perTriangle[sampled->survivors[k].triangle];
    std::vector<std::uint32_t> large;
    std::vector<std::uint32_t> rest;
    for (const std::uint32_t t : eligible)
        (perTriangle[t] > kMaxSplatsPerTriangle ? large : rest).push_back(t);
    if (sampled && !large.empty())
        sampled = rest.empty() ? Sampled{} : sample(source, rest, areas, spacing, random);
    if (!sampled)
        return SplatOutcome::TooLarge;

    const std::size_t cost = sampled->kept.size() + large.size();
    if (static_cast<double>(cost) > kMaxSplatShare * static_cast<double>(source.size()))
        return SplatOutcome::NotReducing;

    std::vector<Attributes> attributes(sampled->survivors.size());
    std::vector<Vec3> positions(sampled->survivors.size());
    for (std::size_t i = 0; i < attributes.size(); ++i) {
        attributes[i] = attributesOf(sampled->survivors[i], source);
        positions[i] = sampled->survivors[i].position;
    }
    const float radius = spacing / 2.0f;
    const PointGrid neighbourhood(positions, radius);
    out.points.clear();
    out.points.reserve(sampled->kept.size());
    for (const std::uint32_t k : sampled->kept)
        out.points.push_back(filtered(k, *sampled, attributes, neighbourhood, radius, grid));
    out.triangles.clear();
    out.triangles.reserve(large.size());
    for (const std::uint32_t t : large)
        out.triangles.push_back(source[t]);
    // Plus where the grid moved each splat's centre (half a step an axis).
    out.error = baseError + splatCoverRadius(spacing) + std::sqrt(3.0f) * grid.maxError();
    return SplatOutcome::Kept;
}

} // namespace ff::builder
