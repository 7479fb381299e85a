#pragma once

// World-space sizes of boxes given in an instance's local frame, for the ε rule. An instance
// transform may scale each axis differently, mirror and shear, so no single scale factor turns
// local lengths or areas into world ones: a slab scaled (10, 0.004, 1) is 10 units wide and
// 0.004 thick. These measures take the whole linear part of the transform instead.

#include <glm/glm.hpp>

namespace ff::runtime {

/**
 * The linear part of a local-to-world transform, with what the measures below need of it.
 * Cheap to build (one 3x3 product); built once per transform and frame, used per node.
 */
class TransformMetric {
public:
    /** From a local-to-world affine transform (the translation is ignored). */
    explicit TransformMetric(const glm::mat4& localToWorld) noexcept;

    /**
     * Area in world units² that the box [boxMin, boxMax] (local) covers when seen from
     * `localEye` (local) along the direction from the eye to the box centre: the sum over the
     * three face pairs of each face's world area times |cos| between its world normal and that
     * direction, i.e. the silhouette of the world parallelepiped. 0 with the eye at the centre.
     *
     * A local face with area vector a maps to cof(M) a = det(M) M⁻ᵀ a, so its projection onto a
     * world unit vector d = M t / |M t| (t = eye - centre, local) is |det M| |a · t| / |M t|.
     */
    [[nodiscard]] float projectedArea(
            const glm::vec3& boxMin,
            const glm::vec3& boxMax,
            const glm::vec3& localEye) const noexcept;

    /**
     * World distance from the eye to the nearest point of the box (0 inside): the minimum of
     * |M (p - eye)| over p in the box. Exact (per-axis clamping) when M's columns are
     * orthogonal — any rotation with per-axis scale, mirrored or not; otherwise (shear) found
     * by coordinate descent on the convex quadratic, which converges to the minimum.
     */
    [[nodiscard]] float nearestDistance(
            const glm::vec3& boxMin,
            const glm::vec3& boxMax,
            const glm::vec3& localEye) const noexcept;

    /** The most a local length can grow in world units (the linear part's largest singular
     *  value; with shear, the Frobenius norm, which bounds it): a stand-in's error in world
     *  units is at most its local error times this, whatever the instance's per-axis scale. */
    [[nodiscard]] float maxStretch() const noexcept { return mMaxStretch; }

    /** Squared world length of the local vector v (orders children by world distance). */
    [[nodiscard]] float worldLengthSquared(const glm::vec3& v) const noexcept {
        const glm::vec3 world = mLinear * v;
        return glm::dot(world, world);
    }

private:
    glm::mat3 mLinear;       ///< the transform's linear part M
    glm::mat3 mGram;         ///< Mᵀ M: |M v|² = vᵀ (Mᵀ M) v
    float mAbsDeterminant;   ///< |det M|: local volume to world volume
    bool mOrthogonalColumns; ///< Mᵀ M is diagonal: no shear, clamping is exact
    float mMaxStretch;       ///< maxStretch()
};

} // namespace ff::runtime
