#pragma once

// The hierarchical-Z test of `--occlusion-backend hzb`: a max-depth pyramid over the depth drawn
// so far, and a conservative box test against it. CPU only (the renderer reads the depth back).

#include <ff/runtime/Traversal.h>

#include <glm/glm.hpp>

#include <cstdint>
#include <span>
#include <vector>

namespace ff::runtime {

/**
 * Level 0 is the depth image (window depth in [0, 1], row 0 at the bottom); each level above
 * holds, per texel, the farthest depth of the 2x2 texels below it. Sizes halve rounding up, so
 * a level of odd width keeps a last column that covers the single column below it: every
 * texel below is covered (a pyramid that rounds down drops the last row and column and hides
 * what is drawn there, a known source of false culling).
 */
class DepthPyramid {
public:
    /** Rebuilds from a width x height depth image. */
    void build(int width, int height, std::span<const float> depth);

    int width() const noexcept { return mWidths.empty() ? 0 : mWidths[0]; }
    int height() const noexcept { return mHeights.empty() ? 0 : mHeights[0]; }
    int levels() const noexcept { return static_cast<int>(mLevels.size()); }
    float at(int level, int x, int y) const {
        return mLevels[static_cast<std::size_t>(level)]
                      [static_cast<std::size_t>(y) *
                               static_cast<std::size_t>(mWidths[static_cast<std::size_t>(level)]) +
                       static_cast<std::size_t>(x)];
    }

    /**
     * Whether something at depth `nearest` over the pixels [x0, x1] x [y0, y1] (inclusive,
     * clamped to the image) could pass a <= depth test: read at the coarsest level where the
     * rectangle spans at most kTexelsPerSide texels a side, and where a texel there may pass,
     * at the quarters of it that meet the rectangle, down to kRefineLevels levels finer.
     */
    bool mayPass(int x0, int y0, int x1, int y1, float nearest) const;

    static constexpr int kTexelsPerSide = 4;
    /** At most 2^4 = 16 times finer than the first level read: 64 x 64 texels a rectangle. */
    static constexpr int kRefineLevels = 4;

private:
    struct Rect {
        int x0, y0, x1, y1; ///< pixels, inclusive
    };
    bool passesWithin(int level, int x, int y, const Rect& rect, float nearest, int finest) const;

    std::vector<std::vector<float>> mLevels;
    std::vector<int> mWidths;
    std::vector<int> mHeights;
};

/**
 * Tests a box (world corners) seen through `viewProjection` on a width x height target against
 * the pyramid: visible unless every pixel its screen rectangle covers holds a nearer depth than
 * the box's nearest corner. A box reaching behind the near plane is visible (its rectangle is
 * unbounded).
 */
bool boxMayBeVisible(
        const DepthPyramid& pyramid,
        const OcclusionBox& box,
        const glm::mat4& viewProjection,
        int width,
        int height);

} // namespace ff::runtime
