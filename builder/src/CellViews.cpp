#include "CellViews.h"

#include <ff/storage/Assert.h>
#include <ff/storage/VertexCodec.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>

namespace ff::builder {

namespace {

int axisOf(int view) {
    return view / 2;
}

float signOf(int view) {
    return view % 2 == 0 ? 1.0f : -1.0f;
}

/** A vertex as the views shade it: its colour, and how much each axis's light reaches it. */
struct Lit {
    std::array<float, 3> colour{};
    std::array<float, 3> light{1.0f, 1.0f, 1.0f}; ///< by axis: 0.25 + 0.75 |n·axis|; 1 unlit

    explicit Lit(const storage::PackedVertex& v)
        : colour{static_cast<float>(v.color[0]), static_cast<float>(v.color[1]), static_cast<float>(v.color[2])} {
        if (storage::isUnlitNormal(v.normalOct))
            return;
        const std::array<float, 3> n = storage::decodeOctNormal(v.normalOct);
        for (std::size_t a = 0; a < 3; ++a)
            light[a] = 0.25f + 0.75f * std::min(std::abs(n[a]), 1.0f);
    }
    /** Its colour seen along `axis`, lit from the eye. */
    [[nodiscard]] std::array<float, 3> along(int axis) const noexcept {
        const float l = light[static_cast<std::size_t>(axis)];
        return {colour[0] * l, colour[1] * l, colour[2] * l};
    }
};

bool finite(const std::array<float, 3>& p) {
    return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
}

} // namespace

CellViews::CellViews(const glm::vec3& boundsMin, const glm::vec3& boundsMax, int resolution)
    : mMin(boundsMin), mResolution(resolution) {
    FF_ASSERT(resolution > 0);
    const glm::vec3 extent = boundsMax - boundsMin;
    const float side = std::max({extent.x, extent.y, extent.z});
    mPixel = side > 0.0f ? side / static_cast<float>(resolution) : 1.0f;
    for (std::vector<Pixel>& v : mViews)
        v.assign(static_cast<std::size_t>(resolution) * static_cast<std::size_t>(resolution), Pixel{});
}

CellViews::Projected CellViews::project(int view, const std::array<float, 3>& p) const noexcept {
    const int axis = axisOf(view);
    const auto u = static_cast<std::size_t>((axis + 1) % 3);
    const auto w = static_cast<std::size_t>((axis + 2) % 3);
    return {(p[u] - mMin[static_cast<glm::length_t>(u)]) / mPixel,
            (p[w] - mMin[static_cast<glm::length_t>(w)]) / mPixel,
            signOf(view) * p[static_cast<std::size_t>(axis)]};
}

void CellViews::plot(int view, int x, int y, float depth, const std::array<float, 3>& shade) {
    Pixel& pixel = mViews[static_cast<std::size_t>(view)]
                         [static_cast<std::size_t>(y) * static_cast<std::size_t>(mResolution) +
                          static_cast<std::size_t>(x)];
    if (pixel.covered && pixel.depth >= depth)
        return;
    pixel.covered = true;
    pixel.depth = depth;
    for (std::size_t c = 0; c < 3; ++c)
        pixel.shade[c] = static_cast<std::uint8_t>(std::clamp(std::lround(shade[c]), 0l, 255l));
}

void CellViews::drawTriangles(std::span<const storage::PackedTriangle> triangles) {
    const float last = static_cast<float>(mResolution - 1);
    for (const storage::PackedTriangle& t : triangles) {
        if (!finite(t.vertices[0].position) || !finite(t.vertices[1].position) ||
            !finite(t.vertices[2].position))
            continue;
        const std::array<Lit, 3> lit = {Lit(t.vertices[0]), Lit(t.vertices[1]), Lit(t.vertices[2])};
        for (int view = 0; view < kViews; ++view) {
            const int axis = axisOf(view);
            std::array<Projected, 3> p;
            std::array<std::array<float, 3>, 3> shade;
            for (std::size_t c = 0; c < 3; ++c) {
                p[c] = project(view, t.vertices[c].position);
                shade[c] = lit[c].along(axis);
            }
            const float area = (p[1].x - p[0].x) * (p[2].y - p[0].y) - (p[2].x - p[0].x) * (p[1].y - p[0].y);
            if (!(std::abs(area) > 0.0f)) {
                // Edge-on from here: conservatively, its edges (a surface seen edge-on is a
                // line within a pixel of where it is, as its splats would show it).
                for (std::size_t k = 0; k < 3; ++k)
                    drawEdge(view, p[k], p[(k + 1) % 3], shade[k], shade[(k + 1) % 3]);
                continue;
            }
            // Conservative: a pixel is covered where the triangle overlaps its square, so a
            // sliver seen edge-on, thinner than a pixel, still shows, as a stand-in's points
            // always do (its own pixel at least); weights clamped to the triangle.
            const float minX = std::max(0.0f, std::floor(std::min({p[0].x, p[1].x, p[2].x})));
            const float maxX = std::min(last, std::floor(std::max({p[0].x, p[1].x, p[2].x})));
            const float minY = std::max(0.0f, std::floor(std::min({p[0].y, p[1].y, p[2].y})));
            const float maxY = std::min(last, std::floor(std::max({p[0].y, p[1].y, p[2].y})));
            // Edge k is opposite corner k: its weight's change per pixel in x and y.
            std::array<float, 3> slack{};
            for (std::size_t k = 0; k < 3; ++k) {
                const Projected& a = p[(k + 1) % 3];
                const Projected& b = p[(k + 2) % 3];
                slack[k] = 0.5f * (std::abs(b.y - a.y) + std::abs(b.x - a.x)) / std::abs(area);
            }
            for (float y = minY; y <= maxY; y += 1.0f)
                for (float x = minX; x <= maxX; x += 1.0f) {
                    const float cx = x + 0.5f;
                    const float cy = y + 0.5f;
                    // Barycentric weights by sub-areas, at the pixel's centre.
                    std::array<float, 3> w = {
                            ((p[1].x - cx) * (p[2].y - cy) - (p[2].x - cx) * (p[1].y - cy)) / area,
                            ((p[2].x - cx) * (p[0].y - cy) - (p[0].x - cx) * (p[2].y - cy)) / area,
                            0.0f};
                    w[2] = 1.0f - w[0] - w[1];
                    if (w[0] < -slack[0] || w[1] < -slack[1] || w[2] < -slack[2])
                        continue;
                    float sum = 0.0f;
                    for (float& weight : w)
                        sum += weight = std::max(weight, 0.0f);
                    if (!(sum > 0.0f))
                        continue;
                    std::array<float, 3> colour{};
                    float depth = 0.0f;
                    for (std::size_t k = 0; k < 3; ++k) {
                        const float weight = w[k] / sum;
                        depth += weight * p[k].depth;
                        for (std::size_t c = 0; c < 3; ++c)
                            colour[c] += weight * shade[k][c];
                    }
                    plot(view, static_cast<int>(x), static_cast<int>(y), depth, colour);
                }
        }
    }
}

void CellViews::drawEdge(
        int view,
        const Projected& a,
        const Projected& b,
        const std::array<float, 3>& shadeA,
        const std::array<float, 3>& shadeB) {
    if (!std::isfinite(a.x) || !std::isfinite(a.y) || !std::isfinite(b.x) || !std::isfinite(b.y))
        return;
    // Clipped to the raster and a pixel around it (Liang-Barsky), so what is cast to int is small.
    const float dx = b.x - a.x;
    const float dy = b.y - a.y;
    const float lo = -1.0f;
    const float hi = static_cast<float>(mResolution + 1);
    float t0 = 0.0f;
    float t1 = 1.0f;
    const auto clip = [&](float p, float q) { // keeps the part where p t <= q
        if (p == 0.0f)
            return q >= 0.0f;
        const float r = q / p;
        if (p < 0.0f)
            t0 = std::max(t0, r);
        else
            t1 = std::min(t1, r);
        return t0 <= t1;
    };
    if (!clip(-dx, a.x - lo) || !clip(dx, hi - a.x) || !clip(-dy, a.y - lo) || !clip(dy, hi - a.y))
        return;
    // Half a pixel a step along the longer axis: at most ~2 (resolution + 2) steps.
    const float length = std::max(std::abs(dx), std::abs(dy)) * (t1 - t0);
    const int steps = static_cast<int>(std::ceil(2.0f * std::min(length, hi - lo))) + 1;
    for (int i = 0; i <= steps; ++i) {
        const float t = t0 + (t1 - t0) * static_cast<float>(i) / static_cast<float>(steps);
        const int x = static_cast<int>(std::floor(std::clamp(a.x + t * dx, lo, hi)));
        const int y = static_cast<int>(std::floor(std::clamp(a.y + t * dy, lo, hi)));
        if (x < 0 || y < 0 || x >= mResolution || y >= mResolution)
            continue;
        std::array<float, 3> shade{};
        for (std::size_t c = 0; c < 3; ++c)
            shade[c] = shadeA[c] + t * (shadeB[c] - shadeA[c]);
        plot(view, x, y, a.depth + t * (b.depth - a.depth), shade);
    }
}

void CellViews::drawSplats(std::span<const storage::PackedVertex> points, float diameter) {
    // A disc wider than the raster covers it all; a bad diameter draws the point's pixel.
    const float size = static_cast<float>(mResolution);
    const float radius = std::isfinite(diameter) ? std::clamp(0.5f * diameter / mPixel, 0.5f, size + 2.0f) : 0.5f;
    const int reach = static_cast<int>(std::ceil(radius));
    for (const storage::PackedVertex& point : points) {
        if (!finite(point.position))
            continue;
        const Lit lit(point);
        for (int view = 0; view < kViews; ++view) {
            const Projected p = project(view, point.position);
            if (!(p.x > -radius - 1.0f && p.x < size + radius + 1.0f && p.y > -radius - 1.0f &&
                  p.y < size + radius + 1.0f))
                continue; // off the raster (or not finite)
            const std::array<float, 3> shade = lit.along(axisOf(view));
            const int px = static_cast<int>(std::floor(p.x));
            const int py = static_cast<int>(std::floor(p.y));
            for (int y = std::max(py - reach, 0); y <= std::min(py + reach, mResolution - 1); ++y)
                for (int x = std::max(px - reach, 0); x <= std::min(px + reach, mResolution - 1); ++x) {
                    const float dx = static_cast<float>(x) + 0.5f - p.x;
                    const float dy = static_cast<float>(y) + 0.5f - p.y;
                    if ((x == px && y == py) || dx * dx + dy * dy <= radius * radius)
                        plot(view, x, y, p.depth, shade);
                }
        }
    }
}

namespace {

/** How far `a`'s pixel (x, y) shades from the nearest in shade of `b`'s covered pixels within
 *  `reach` (the largest channel's difference, 8-bit steps): 0 where `a` covers nothing there,
 *  256 where `b` covers nothing near. */
int nearestShade(
        std::span<const CellViews::Pixel> a,
        std::span<const CellViews::Pixel> b,
        int resolution,
        int x,
        int y,
        int reach) {
    const CellViews::Pixel& p = a[static_cast<std::size_t>(y * resolution + x)];
    if (!p.covered)
        return 0;
    int best = 256;
    for (int dy = -reach; dy <= reach; ++dy)
        for (int dx = -reach; dx <= reach; ++dx) {
            const int nx = x + dx;
            const int ny = y + dy;
            if (nx < 0 || ny < 0 || nx >= resolution || ny >= resolution)
                continue;
            const CellViews::Pixel& q = b[static_cast<std::size_t>(ny * resolution + nx)];
            if (!q.covered)
                continue;
            int difference = 0;
            for (std::size_t c = 0; c < 3; ++c)
                difference = std::max(difference, std::abs(int{p.shade[c]} - int{q.shade[c]}));
            best = std::min(best, difference);
        }
    return best;
}

} // namespace

ViewDifference viewDifference(const CellViews& a, const CellViews& b, int reach, float shadeStep) {
    FF_ASSERT(a.resolution() == b.resolution());
    const int r = a.resolution();
    std::uint64_t either = 0;
    std::uint64_t mismatched = 0;
    double sum = 0.0;
    for (int v = 0; v < CellViews::kViews; ++v) {
        const std::span<const CellViews::Pixel> va = a.view(v);
        const std::span<const CellViews::Pixel> vb = b.view(v);
        for (int y = 0; y < r; ++y)
            for (int x = 0; x < r; ++x) {
                const auto i = static_cast<std::size_t>(y * r + x);
                if (!va[i].covered && !vb[i].covered)
                    continue;
                ++either;
                const int difference =
                        std::min(255, std::max(nearestShade(va, vb, r, x, y, reach), nearestShade(vb, va, r, x, y, reach)));
                sum += difference;
                mismatched += static_cast<float>(difference) > shadeStep ? 1u : 0u;
            }
    }
    if (either == 0)
        return {};
    return {static_cast<double>(mismatched) / static_cast<double>(either), sum / static_cast<double>(either)};
}

} // namespace ff::builder
