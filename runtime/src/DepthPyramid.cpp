#include "DepthPyramid.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace ff::runtime {

namespace {

/** Depth readback is quantised (24-bit): a box face lying on a drawn surface must not be found
 *  behind it by a rounding. */
constexpr float kDepthSlack = 1.0f / (1 << 22);

} // namespace

void DepthPyramid::build(int width, int height, std::span<const float> depth) {
    mLevels.clear();
    mWidths.clear();
    mHeights.clear();
    if (width <= 0 || height <= 0)
        return;
    mLevels.emplace_back(
            depth.begin(), depth.begin() + static_cast<std::ptrdiff_t>(width) * height);
    mWidths.push_back(width);
    mHeights.push_back(height);
    while (mWidths.back() > 1 || mHeights.back() > 1) {
        const int w = mWidths.back();
        const int h = mHeights.back();
        const int cw = (w + 1) / 2;
        const int ch = (h + 1) / 2;
        const std::vector<float>& below = mLevels.back();
        std::vector<float> level(static_cast<std::size_t>(cw) * static_cast<std::size_t>(ch));
        for (int y = 0; y < ch; ++y)
            for (int x = 0; x < cw; ++x) {
                float farthest = 0.0f;
                for (int dy = 0; dy < 2; ++dy)
                    for (int dx = 0; dx < 2; ++dx) {
                        const int sx = std::min(2 * x + dx, w - 1);
                        const int sy = std::min(2 * y + dy, h - 1);
                        farthest = std::max(
                                farthest,
                                below[static_cast<std::size_t>(sy) * static_cast<std::size_t>(w) +
                                      static_cast<std::size_t>(sx)]);
                    }
                level[static_cast<std::size_t>(y) * static_cast<std::size_t>(cw) +
                      static_cast<std::size_t>(x)] = farthest;
            }
        mLevels.push_back(std::move(level));
        mWidths.push_back(cw);
        mHeights.push_back(ch);
    }
}

bool DepthPyramid::mayPass(int x0, int y0, int x1, int y1, float nearest) const {
    if (mLevels.empty())
        return true;
    const Rect rect{
            std::clamp(x0, 0, width() - 1),
            std::clamp(y0, 0, height() - 1),
            std::clamp(x1, 0, width() - 1),
            std::clamp(y1, 0, height() - 1)};
    int level = 0;
    while (level + 1 < levels() && ((rect.x1 >> level) - (rect.x0 >> level) >= kTexelsPerSide ||
                                    (rect.y1 >> level) - (rect.y0 >> level) >= kTexelsPerSide))
        ++level;
    const int finest = std::max(0, level - kRefineLevels);
    // Texel t of level l covers the pixels [t * 2^l, (t + 1) * 2^l): the rectangle's texels.
    for (int y = rect.y0 >> level; y <= rect.y1 >> level; ++y)
        for (int x = rect.x0 >> level; x <= rect.x1 >> level; ++x)
            if (passesWithin(level, x, y, rect, nearest, finest))
                return true;
    return false;
}

bool DepthPyramid::passesWithin(
        int level, int x, int y, const Rect& rect, float nearest, int finest) const {
    if (nearest > at(level, x, y) + kDepthSlack)
        return false; // hidden over all this texel covers
    if (level == finest)
        return true;
    // A coarse texel also covers pixels outside the rectangle (past an occluder's edge, say):
    // its quarters that meet the rectangle decide.
    const int below = level - 1;
    const auto index = static_cast<std::size_t>(below);
    for (int cy = std::max(2 * y, rect.y0 >> below);
         cy <= std::min({2 * y + 1, rect.y1 >> below, mHeights[index] - 1});
         ++cy)
        for (int cx = std::max(2 * x, rect.x0 >> below);
             cx <= std::min({2 * x + 1, rect.x1 >> below, mWidths[index] - 1});
             ++cx)
            if (passesWithin(below, cx, cy, rect, nearest, finest))
                return true;
    return false;
}

bool boxMayBeVisible(
        const DepthPyramid& pyramid,
        const OcclusionBox& box,
        const glm::mat4& viewProjection,
        int width,
        int height) {
    glm::vec2 lo(std::numeric_limits<float>::infinity());
    glm::vec2 hi(-std::numeric_limits<float>::infinity());
    float nearest = std::numeric_limits<float>::infinity();
    for (const glm::vec3& corner : box.corners) {
        const glm::vec4 clip = viewProjection * glm::vec4(corner, 1.0f);
        if (!(clip.w > 0.0f) || clip.z < -clip.w)
            return true; // behind the near plane
        const glm::vec3 ndc = glm::vec3(clip) / clip.w;
        const glm::vec2 window(
                (ndc.x * 0.5f + 0.5f) * static_cast<float>(width),
                (ndc.y * 0.5f + 0.5f) * static_cast<float>(height));
        lo = glm::min(lo, window);
        hi = glm::max(hi, window);
        nearest = std::min(nearest, ndc.z * 0.5f + 0.5f);
    }
    if (hi.x < 0.0f || hi.y < 0.0f || lo.x >= static_cast<float>(width) ||
        lo.y >= static_cast<float>(height))
        return true; // off screen: the frustum's business, not depth's
    // Every pixel whose centre the box may cover, and one more each side for rounding.
    return pyramid.mayPass(
            static_cast<int>(std::floor(lo.x)) - 1,
            static_cast<int>(std::floor(lo.y)) - 1,
            static_cast<int>(std::floor(hi.x)) + 1,
            static_cast<int>(std::floor(hi.y)) + 1,
            nearest);
}

} // namespace ff::runtime
