#include <ff/runtime/Camera.h>

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>

namespace ff::runtime {

Camera Camera::lookAt(const glm::vec3& eye, const glm::vec3& target, const glm::vec3& upHint, float fovY) {
    Camera camera;
    camera.eye = eye;
    glm::vec3 forward = target - eye;
    if (!(glm::dot(forward, forward) > 0.0f))
        forward = {0.0f, 0.0f, -1.0f};
    camera.forward = glm::normalize(forward);
    glm::vec3 right = glm::cross(camera.forward, upHint);
    if (!(glm::dot(right, right) > 1e-12f)) // looking along the hint: any perpendicular will do
        right = glm::cross(camera.forward, std::fabs(camera.forward.y) < 0.9f ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0));
    right = glm::normalize(right);
    camera.up = glm::cross(right, camera.forward);
    camera.fovY = fovY;
    return camera;
}

Camera Camera::orbit(
        const Bounds& bounds, float distanceRadii, float azimuthDegrees, float elevationDegrees, float fovY) {
    const float azimuth = glm::radians(azimuthDegrees);
    const float elevation = glm::radians(elevationDegrees);
    const glm::vec3 direction(
            std::cos(elevation) * std::sin(azimuth), std::sin(elevation), std::cos(elevation) * std::cos(azimuth));
    const float radius = std::max(bounds.radius(), 1e-6f);
    Camera camera = lookAt(bounds.center() + direction * (distanceRadii * radius), bounds.center(), {0, 1, 0}, fovY);
    camera.fitClipPlanes(bounds);
    return camera;
}

void Camera::fitClipPlanes(const Bounds& bounds) {
    // Distances along the view axis of the box corners.
    float nearest = INFINITY;
    float farthest = -INFINITY;
    for (int k = 0; k < 8; ++k) {
        const glm::vec3 corner((k & 1) ? bounds.max.x : bounds.min.x, (k & 2) ? bounds.max.y : bounds.min.y,
                               (k & 4) ? bounds.max.z : bounds.min.z);
        const float d = glm::dot(corner - eye, forward);
        nearest = std::min(nearest, d);
        farthest = std::max(farthest, d);
    }
    zFar = std::max(farthest * 1.01f, 1e-3f);
    if (orthographic) {
        zNear = nearest - 0.01f * (farthest - nearest) - 1e-3f;
        return;
    }
    zNear = std::max(nearest * 0.99f, zFar * 1e-5f);
}

glm::mat4 Camera::view() const { return glm::lookAt(eye, eye + forward, up); }

glm::mat4 Camera::projection(float aspect) const {
    if (orthographic) {
        const float h = orthoHalfHeight;
        return glm::ortho(-h * aspect, h * aspect, -h, h, zNear, zFar);
    }
    return glm::perspective(fovY, aspect, zNear, zFar);
}

float Camera::pixelScale(float heightPixels) const {
    if (orthographic)
        return 0.5f * heightPixels / orthoHalfHeight;
    return 0.5f * heightPixels / std::tan(0.5f * fovY);
}

} // namespace ff::runtime
