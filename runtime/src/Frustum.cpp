#include <ff/runtime/Frustum.h>

#include <cmath>

namespace ff::runtime {

Frustum::Frustum(const glm::mat4& m) {
    const glm::vec4 row0(m[0][0], m[1][0], m[2][0], m[3][0]);
    const glm::vec4 row1(m[0][1], m[1][1], m[2][1], m[3][1]);
    const glm::vec4 row2(m[0][2], m[1][2], m[2][2], m[3][2]);
    const glm::vec4 row3(m[0][3], m[1][3], m[2][3], m[3][3]);
    mPlanes = {row3 + row0, row3 - row0, row3 + row1, row3 - row1, row3 + row2, row3 - row2};
}

bool Frustum::intersects(const glm::vec3& boxMin, const glm::vec3& boxMax) const {
    for (const glm::vec4& plane : mPlanes) {
        // The box corner furthest along the plane normal.
        const glm::vec3 p(plane.x >= 0.0f ? boxMax.x : boxMin.x, plane.y >= 0.0f ? boxMax.y : boxMin.y,
                          plane.z >= 0.0f ? boxMax.z : boxMin.z);
        if (plane.x * p.x + plane.y * p.y + plane.z * p.z + plane.w < 0.0f)
            return false;
    }
    return true;
}

void transformBox(const glm::mat4& transform, const glm::vec3& localMin, const glm::vec3& localMax,
                  glm::vec3& worldMin, glm::vec3& worldMax) {
    const glm::vec3 center = 0.5f * (localMin + localMax);
    const glm::vec3 half = 0.5f * (localMax - localMin);
    const glm::vec3 worldCenter(transform * glm::vec4(center, 1.0f));
    glm::vec3 worldHalf(0.0f);
    for (int col = 0; col < 3; ++col)
        worldHalf += glm::abs(glm::vec3(transform[col])) * half[col];
    worldMin = worldCenter - worldHalf;
    worldMax = worldCenter + worldHalf;
}

} // namespace ff::runtime
