#include <ff/builder/SceneSink.h>
#include <ff/storage/VertexCodec.h>

#include <cmath>

namespace ff::builder {

namespace {

bool isUsableNormal(const glm::vec3& n) {
    const float len2 = glm::dot(n, n);
    return std::isfinite(len2) && len2 > 1e-12f;
}

} // namespace

storage::PackedVertex packVertex(const SourceVertex& v, const glm::vec3& fallbackNormal) noexcept {
    const glm::vec3 n = isUsableNormal(v.normal) ? v.normal : fallbackNormal;
    storage::PackedVertex out{};
    out.position = {v.position.x, v.position.y, v.position.z};
    out.normalOct = v.unlit ? storage::kUnlitNormalOct : storage::encodeOctNormal(n.x, n.y, n.z);
    out.color = {
            storage::linearToSrgb8(v.color.r),
            storage::linearToSrgb8(v.color.g),
            storage::linearToSrgb8(v.color.b),
            storage::toUnorm8(v.color.a)};
    return out;
}

storage::PackedTriangle packTriangle(
        const SourceVertex& a, const SourceVertex& b, const SourceVertex& c) noexcept {
    const glm::vec3 faceNormal = glm::cross(b.position - a.position, c.position - a.position);
    return {{packVertex(a, faceNormal), packVertex(b, faceNormal), packVertex(c, faceNormal)}};
}

} // namespace ff::builder
