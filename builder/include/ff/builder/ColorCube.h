#pragma once

// Color cubes (Chamberlain et al. '96, §3-4): the far-field appearance of a cell as six
// premultiplied RGBA faces, each the cell's content seen through an orthographic projection
// along the face normal, with alpha = the fraction of the face the content covers.
//
// Leaves are baked by rasterising their triangles through each face into resolution x
// resolution samples (nearest surface per sample, coverage -> alpha) and averaging. Inner nodes
// composite their children front-over-back and average the four results (the paper's Fig. 3);
// a node's own (large) triangles cover the children where they hit a sample. Instance-level
// nodes composite transformed boxes of their prototypes' approximations.

#include <ff/storage/SceneFormat.h>

#include <glm/glm.hpp>

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace ff::builder {

/** Faces in storage order (-X, +X, -Y, +Y, -Z, +Z); premultiplied linear RGBA in [0,1]. */
struct ColorCube {
    std::array<glm::vec4, storage::kCubeFaceCount> faces{};
};

/** Rounds each channel to unorm8 (the NodeRecord encoding). */
std::array<std::array<std::uint8_t, 4>, storage::kCubeFaceCount> quantizeCube(const ColorCube& cube);
ColorCube dequantizeCube(const std::array<std::array<std::uint8_t, 4>, storage::kCubeFaceCount>& bytes);

/** `front` over `back`, premultiplied (Porter-Duff). */
inline glm::vec4 over(const glm::vec4& front, const glm::vec4& back) {
    return front + (1.0f - front.a) * back;
}

/**
 * The per-face, per-quadrant composite of eight octant children: for face f and quadrant
 * (qu, qv) of the face's two in-plane axes, the child nearer the face's viewer over the one
 * behind it. Missing children (nullptr) are transparent. Index: [face][qu + 2 * qv].
 */
using QuadrantColors = std::array<std::array<glm::vec4, 4>, storage::kCubeFaceCount>;
QuadrantColors compositeOctantQuadrants(const std::array<const ColorCube*, 8>& children);

/** Fig. 3: composite front over back, then average the four quadrants. */
ColorCube compositeOctants(const std::array<const ColorCube*, 8>& children);

/** In-plane axes of the faces on `axis`: u = (axis + 1) % 3, v = (axis + 2) % 3. */
inline int faceAxisU(int axis) { return (axis + 1) % 3; }
inline int faceAxisV(int axis) { return (axis + 2) % 3; }

/**
 * Bakes one cell's color cube from sampled content. Reusable: reset() starts a new cell.
 * Not thread-safe; use one baker per thread.
 */
class CubeBaker {
public:
    /** `resolution` samples along each face edge (at least 2; farfield defaults to 8). */
    explicit CubeBaker(int resolution);

    int resolution() const noexcept { return mResolution; }

    /** Starts a new cell whose faces lie on the box [cellMin, cellMax]. */
    void reset(const glm::vec3& cellMin, const glm::vec3& cellMax);

    /** Rasterises opaque triangles (cell coordinates) into the six face grids, keeping the
     *  nearest surface per sample and face. Colours are shaded with the shading model. */
    void addTriangles(std::span<const storage::PackedTriangle> triangles);

    /** Adds a translucent box (e.g. a prototype cell) given in its own frame and placed by
     *  `transform`; each face grid sees the box's faces that look its way, coloured by `cube`. */
    void addBox(
            const glm::mat4& transform,
            const glm::vec3& boxMin,
            const glm::vec3& boxMax,
            const ColorCube& cube);

    /**
     * The cube: per sample, the nearest triangle if one covers it, else the added boxes
     * composited front to back over `underlay`'s quadrant colour (if given); averaged over
     * the face.
     */
    ColorCube finish(const QuadrantColors* underlay = nullptr);

    /** Samples per face covered by triangles since reset() (for tests and statistics). */
    int coveredSamples(int face) const;

private:
    struct Fragment {
        float depth;
        glm::vec4 color; ///< premultiplied
        int sample;
    };
    struct AxisGrid {
        std::vector<float> minDepth; ///< nearest surface seen from the -axis face
        std::vector<float> maxDepth; ///< nearest surface seen from the +axis face
        std::vector<glm::vec3> minColor;
        std::vector<glm::vec3> maxColor;
    };

    void rasterizeTriangle(int axis, const std::array<glm::vec3, 3>& p, const std::array<glm::vec3, 3>& c);
    void rasterizeBoxFace(
            int face, const std::array<glm::vec3, 4>& corners, float depth, const glm::vec4& color);

    int mResolution;
    glm::vec3 mCellMin{0.0f};
    glm::vec3 mCellMax{1.0f};
    std::array<AxisGrid, 3> mGrids;
    std::array<std::vector<Fragment>, storage::kCubeFaceCount> mBoxFragments;
};

} // namespace ff::builder
