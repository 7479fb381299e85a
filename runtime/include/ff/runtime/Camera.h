#pragma once

#include <glm/glm.hpp>

namespace ff::runtime {

/** World bounds of what is to be seen (e.g. the scene header's bounds). */
struct Bounds {
    glm::vec3 min{0.0f};
    glm::vec3 max{0.0f};
    glm::vec3 center() const { return 0.5f * (min + max); }
    /** Radius of the bounding sphere through the corners. */
    float radius() const { return 0.5f * glm::length(max - min); }
};

/**
 * A pinhole (or orthographic) camera. Angles in radians, distances in world units. Near and far
 * planes are fitted to the scene with fitClipPlanes() so depth precision follows the scene.
 */
struct Camera {
    glm::vec3 eye{0.0f, 0.0f, 5.0f};
    glm::vec3 forward{0.0f, 0.0f, -1.0f}; ///< unit
    glm::vec3 up{0.0f, 1.0f, 0.0f};       ///< unit, orthogonal to forward
    float fovY = 0.7853982f;              ///< vertical field of view (perspective)
    bool orthographic = false;
    float orthoHalfHeight = 1.0f; ///< orthographic: half the view height in world units
    float zNear = 0.01f;
    float zFar = 1000.0f;

    /** Looks from `eye` at `target`; `upHint` need not be orthogonal. */
    static Camera lookAt(const glm::vec3& eye, const glm::vec3& target, const glm::vec3& upHint, float fovY);

    /**
     * Chamberlain et al.'s views: at `distanceRadii` scene radii from the bounds' centre, turned
     * `azimuthDegrees` about +Y from the +Z axis and raised `elevationDegrees` towards +Y,
     * looking at the centre.
     */
    static Camera orbit(
            const Bounds& bounds, float distanceRadii, float azimuthDegrees, float elevationDegrees, float fovY);

    /** Sets zNear/zFar to enclose `bounds` tightly (near never below far / 1e5). */
    void fitClipPlanes(const Bounds& bounds);

    glm::mat4 view() const;
    glm::mat4 projection(float aspect) const;

    /** Pixels per world unit at distance 1 for a viewport `heightPixels` tall (perspective), or
     *  pixels per world unit (orthographic). */
    float pixelScale(float heightPixels) const;
};

} // namespace ff::runtime
