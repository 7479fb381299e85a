#pragma once

// A cell seen from its six face directions on a small orthographic raster: how the builder
// compares a stand-in with the geometry it stands for (issue 17: the choice per node by
// measured error). Depth-tested, shaded with a light from the eye (a vertex's sRGB colour times
// 0.25 + 0.75 |n·view|; unlit vertices keep their colour), Gouraud-interpolated, no blending:
// what the runtime draws, at the size where a stand-in is first drawn.

#include <ff/storage/SceneFormat.h>

#include <glm/vec3.hpp>

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace ff::builder {

class CellViews {
public:
    /** Six views of the box [boundsMin, boundsMax], each `resolution` pixels across its largest
     *  side (the box fits every view). */
    CellViews(const glm::vec3& boundsMin, const glm::vec3& boundsMax, int resolution);

    /** Draws triangles, conservatively: a pixel is covered where a triangle overlaps it, so
     *  geometry thinner than a pixel seen edge-on still shows, and one seen exactly edge-on (or
     *  degenerate) draws its edges; non-finite ones are skipped. */
    void drawTriangles(std::span<const storage::PackedTriangle> triangles);
    /** Draws splats as discs of `diameter` (box units) around each point, at least the pixel
     *  each point falls in, as the runtime's points are at least a pixel. */
    void drawSplats(std::span<const storage::PackedVertex> points, float diameter);

    [[nodiscard]] int resolution() const noexcept { return mResolution; }
    /** The size of a pixel in box units. */
    [[nodiscard]] float pixelSize() const noexcept { return mPixel; }

    struct Pixel {
        float depth = 0.0f; ///< along the view, larger nearer the eye
        std::array<std::uint8_t, 3> shade{};
        bool covered = false;
    };
    static constexpr int kViews = 6;
    /** View `v` (0-5: +x, -x, +y, -y, +z, -z) row by row. */
    [[nodiscard]] std::span<const Pixel> view(int v) const noexcept { return mViews[static_cast<std::size_t>(v)]; }

private:
    struct Projected {
        float x = 0.0f;
        float y = 0.0f;
        float depth = 0.0f;
    };
    [[nodiscard]] Projected project(int view, const std::array<float, 3>& p) const noexcept;
    void plot(int view, int x, int y, float depth, const std::array<float, 3>& shade);
    /** The pixels the segment ab passes through (a triangle seen edge-on). */
    void drawEdge(
            int view,
            const Projected& a,
            const Projected& b,
            const std::array<float, 3>& shadeA,
            const std::array<float, 3>& shadeB);

    glm::vec3 mMin;
    float mPixel = 1.0f;
    int mResolution = 0;
    std::array<std::vector<Pixel>, kViews> mViews;
};

/** How differently two views of a box show it (viewDifference). */
struct ViewDifference {
    /** The share of the pixels either covers that the other shows no match for. */
    double mismatch = 0.0;
    /** Over the same pixels, the mean of each one's difference from its best match, in 8-bit
     *  steps of the largest channel (255 where the other covers nothing near). */
    double meanDifference = 0.0;
};

/**
 * How differently `a` and `b` (views of the same box at the same resolution) show it, over
 * the six views: a pixel either covers is matched by the covered pixel of the other within
 * `reach` pixels (in x and y: the shift a stand-in's error allows) that shades nearest to it,
 * both ways; it mismatches where that is more than `shadeStep` 8-bit steps apart, or there is
 * none. Zeros when neither covers anything.
 */
[[nodiscard]] ViewDifference viewDifference(const CellViews& a, const CellViews& b, int reach, float shadeStep);

} // namespace ff::builder
