#pragma once

#include <glm/glm.hpp>

#include <array>

namespace ff::runtime {

/** The six planes of a view-projection matrix, normals pointing inwards. */
class Frustum {
public:
    explicit Frustum(const glm::mat4& viewProjection);

    /** False only if the box is certainly outside (conservative: may keep some outside boxes). */
    bool intersects(const glm::vec3& boxMin, const glm::vec3& boxMax) const;

private:
    std::array<glm::vec4, 6> mPlanes;
};

/** World bounds of a local box under an affine transform. */
void transformBox(const glm::mat4& transform, const glm::vec3& localMin, const glm::vec3& localMax,
                  glm::vec3& worldMin, glm::vec3& worldMax);

} // namespace ff::runtime
