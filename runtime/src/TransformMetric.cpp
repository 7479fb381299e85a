#include <ff/runtime/TransformMetric.h>

#include <algorithm>
#include <cmath>

namespace ff::runtime {

namespace {

/** Sweeps of coordinate descent for sheared transforms. Each sweep shrinks the distance's error
 *  by a factor set by the shear; the loop stops early once no coordinate moves. */
constexpr int kMaxSweeps = 32;

/** Columns count as orthogonal when their cosine is below this. */
constexpr float kOrthogonalCosine = 1e-6f;

} // namespace

TransformMetric::TransformMetric(const glm::mat4& localToWorld) noexcept
    : mLinear(localToWorld)
    , mGram(glm::transpose(mLinear) * mLinear)
    , mAbsDeterminant(std::fabs(glm::determinant(mLinear)))
    , mOrthogonalColumns(true)
    , mMaxStretch(0.0f) {
    for (int i = 0; i < 3; ++i) {
        for (int j = i + 1; j < 3; ++j) {
            if (std::fabs(mGram[i][j]) > kOrthogonalCosine * std::sqrt(mGram[i][i] * mGram[j][j]))
                mOrthogonalColumns = false;
        }
    }
    // Orthogonal columns: the singular values are the column lengths. Otherwise the Frobenius
    // norm, never below the largest singular value.
    mMaxStretch = mOrthogonalColumns
                          ? std::sqrt(std::max({mGram[0][0], mGram[1][1], mGram[2][2]}))
                          : std::sqrt(mGram[0][0] + mGram[1][1] + mGram[2][2]);
}

float TransformMetric::projectedArea(
        const glm::vec3& boxMin,
        const glm::vec3& boxMax,
        const glm::vec3& localEye) const noexcept {
    const glm::vec3 extent = boxMax - boxMin;
    const glm::vec3 toEye = localEye - 0.5f * (boxMin + boxMax);
    const float worldDistance = glm::length(mLinear * toEye);
    if (!(worldDistance > 0.0f))
        return 0.0f;
    const glm::vec3 faceAreas(extent.y * extent.z, extent.z * extent.x, extent.x * extent.y);
    return mAbsDeterminant * glm::dot(faceAreas, glm::abs(toEye)) / worldDistance;
}

float TransformMetric::nearestDistance(
        const glm::vec3& boxMin,
        const glm::vec3& boxMax,
        const glm::vec3& localEye) const noexcept {
    // |M d|² = dᵀ G d is separable per axis when G is diagonal: clamping each coordinate of the
    // eye into the box then gives the nearest point.
    glm::vec3 nearest = glm::clamp(localEye, boxMin, boxMax);
    if (!mOrthogonalColumns) {
        // Minimise dᵀ G d over the box one coordinate at a time: with the others fixed, the
        // quadratic's minimum along axis i is at d_i = -Σ_{j≠i} G_ij d_j / G_ii, then clamped.
        // A convex quadratic over a box: cyclic descent converges to the global minimum.
        const float tolerance = 1e-6f * glm::length(boxMax - boxMin);
        for (int sweep = 0; sweep < kMaxSweeps; ++sweep) {
            float moved = 0.0f;
            for (int i = 0; i < 3; ++i) {
                if (!(mGram[i][i] > 0.0f))
                    continue;
                float coupling = 0.0f;
                for (int j = 0; j < 3; ++j) {
                    if (j != i)
                        coupling += mGram[j][i] * (nearest[j] - localEye[j]);
                }
                const float next =
                        std::clamp(localEye[i] - coupling / mGram[i][i], boxMin[i], boxMax[i]);
                moved = std::max(moved, std::fabs(next - nearest[i]));
                nearest[i] = next;
            }
            if (!(moved > tolerance))
                break;
        }
    }
    return glm::length(mLinear * (nearest - localEye));
}

} // namespace ff::runtime
