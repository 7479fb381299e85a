#include <ff/storage/VertexCodec.h>

#include <algorithm>
#include <cmath>

namespace ff::storage {

namespace {

float signNotZero(float v) noexcept { return v >= 0.0f ? 1.0f : -1.0f; }

std::int16_t toSnorm16(float v) noexcept {
    return static_cast<std::int16_t>(std::lround(std::clamp(v, -1.0f, 1.0f) * 32767.0f));
}

struct SrgbTable {
    std::array<float, 256> toLinear{};
    SrgbTable() {
        for (int i = 0; i < 256; ++i) {
            const double c = i / 255.0;
            toLinear[static_cast<std::size_t>(i)] = static_cast<float>(
                    c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4));
        }
    }
};

const SrgbTable& srgbTable() {
    static const SrgbTable table; // immutable after construction: safe to share
    return table;
}

} // namespace

std::array<std::int16_t, 2> encodeOctNormal(float x, float y, float z) noexcept {
    const float l1 = std::fabs(x) + std::fabs(y) + std::fabs(z);
    if (!(l1 > 0.0f) || !std::isfinite(l1))
        return {0, 0}; // decodes to +Z
    float u = x / l1;
    float v = y / l1;
    if (z < 0.0f) {
        const float pu = u;
        u = (1.0f - std::fabs(v)) * signNotZero(pu);
        v = (1.0f - std::fabs(pu)) * signNotZero(v);
    }
    return {toSnorm16(u), toSnorm16(v)};
}

std::array<float, 3> decodeOctNormal(std::array<std::int16_t, 2> oct) noexcept {
    const float u = std::max(oct[0] / 32767.0f, -1.0f);
    const float v = std::max(oct[1] / 32767.0f, -1.0f);
    float x = u;
    float y = v;
    const float z = 1.0f - std::fabs(u) - std::fabs(v);
    if (z < 0.0f) {
        x = (1.0f - std::fabs(v)) * signNotZero(u);
        y = (1.0f - std::fabs(u)) * signNotZero(v);
    }
    const float len = std::sqrt(x * x + y * y + z * z);
    return {x / len, y / len, z / len};
}

std::uint8_t linearToSrgb8(float linear) noexcept {
    if (!(linear > 0.0f))
        return 0;
    if (linear >= 1.0f)
        return 255;
    const auto& table = srgbTable().toLinear;
    // Nearest code in linear space: binary search the monotonic table, then pick the closer.
    const auto it = std::lower_bound(table.begin(), table.end(), linear);
    const auto hi = static_cast<int>(it - table.begin());
    const int lo = std::max(hi - 1, 0);
    const float dLo = linear - table[static_cast<std::size_t>(lo)];
    const float dHi = table[static_cast<std::size_t>(hi)] - linear;
    return static_cast<std::uint8_t>(dLo <= dHi ? lo : hi);
}

float srgb8ToLinear(std::uint8_t code) noexcept { return srgbTable().toLinear[code]; }

std::uint8_t toUnorm8(float value) noexcept {
    if (!(value > 0.0f))
        return 0;
    return static_cast<std::uint8_t>(std::lround(std::min(value, 1.0f) * 255.0f));
}

} // namespace ff::storage
