#include "TextureSampler.h"

#include <stb_image.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>

namespace ff::builder {

namespace {

constexpr int kMaxTextureSide = 1 << 15;
constexpr int kGltfClampToEdge = 33071;
constexpr int kGltfMirroredRepeat = 33648;

std::array<float, 256> makeSrgbTable() noexcept {
    std::array<float, 256> table{};
    for (std::size_t i = 0; i < table.size(); ++i) {
        const double c = static_cast<double>(i) / 255.0;
        table[i] =
                static_cast<float>(c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4));
    }
    return table;
}

/**
 * Maps a continuous texel coordinate to a finite range where floor() fits an int, keeping the
 * wrap mode's meaning: repeat/mirror reduce by their period, clamp saturates.
 */
double reduce(double x, int size, WrapMode mode) noexcept {
    if (!std::isfinite(x))
        return 0.0;
    const double n = static_cast<double>(size);
    switch (mode) {
    case WrapMode::ClampToEdge:
        return std::clamp(x, -1.0, n);
    case WrapMode::MirroredRepeat:
        return x - 2.0 * n * std::floor(x / (2.0 * n));
    case WrapMode::Repeat:
    default:
        return x - n * std::floor(x / n);
    }
}

int wrapIndex(int i, int size, WrapMode mode) noexcept {
    switch (mode) {
    case WrapMode::ClampToEdge:
        return std::clamp(i, 0, size - 1);
    case WrapMode::MirroredRepeat: {
        const int period = 2 * size;
        const int m = ((i % period) + period) % period;
        return m < size ? m : period - 1 - m;
    }
    case WrapMode::Repeat:
    default:
        return ((i % size) + size) % size;
    }
}

} // namespace

WrapMode wrapModeFromGltf(int wrap) noexcept {
    switch (wrap) {
    case kGltfClampToEdge:
        return WrapMode::ClampToEdge;
    case kGltfMirroredRepeat:
        return WrapMode::MirroredRepeat;
    default:
        return WrapMode::Repeat;
    }
}

float srgb8ToLinear(std::uint8_t value) noexcept {
    static const std::array<float, 256> kTable = makeSrgbTable(); // immutable after init
    return kTable[value];
}

Result<TextureSampler> TextureSampler::decode(std::span<const unsigned char> encoded) {
    if (encoded.empty())
        return Status{ErrorCode::InvalidInput, "image has no data"};
    if (encoded.size() > static_cast<std::size_t>(std::numeric_limits<int>::max()))
        return Status{ErrorCode::Unsupported, "image larger than 2 GiB"};
    const int size = static_cast<int>(encoded.size());
    int width = 0;
    int height = 0;
    int channels = 0;
    if (stbi_info_from_memory(encoded.data(), size, &width, &height, &channels) == 0)
        return Status{ErrorCode::InvalidInput, std::string("image: ") + stbi_failure_reason()};
    if (width <= 0 || height <= 0 || width > kMaxTextureSide || height > kMaxTextureSide)
        return Status{ErrorCode::Unsupported, "image size out of range"};
    stbi_uc* pixels = stbi_load_from_memory(encoded.data(), size, &width, &height, &channels, 4);
    if (pixels == nullptr)
        return Status{ErrorCode::InvalidInput, std::string("image: ") + stbi_failure_reason()};
    const std::size_t bytes =
            static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * 4;
    std::vector<std::uint8_t> rgba(pixels, pixels + bytes);
    stbi_image_free(pixels);
    return TextureSampler(width, height, std::move(rgba), WrapMode::Repeat, WrapMode::Repeat);
}

TextureSampler::TextureSampler(
        int width, int height, std::vector<std::uint8_t> rgba, WrapMode s, WrapMode t)
    : mWidth(width)
    , mHeight(height)
    , mRgba(std::move(rgba))
    , mWrapS(s)
    , mWrapT(t) {
    FF_ASSERT(width > 0 && height > 0);
    FF_ASSERT(
            mRgba.size() == static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * 4);
}

glm::vec4 TextureSampler::texel(int x, int y) const noexcept {
    const std::size_t at = (static_cast<std::size_t>(y) * static_cast<std::size_t>(mWidth) +
                            static_cast<std::size_t>(x)) *
                           4;
    return {srgb8ToLinear(mRgba[at]),
            srgb8ToLinear(mRgba[at + 1]),
            srgb8ToLinear(mRgba[at + 2]),
            static_cast<float>(mRgba[at + 3]) / 255.0f};
}

glm::vec4 TextureSampler::sample(glm::vec2 uv) const noexcept {
    // Texel centres sit at half-integers: u = (i + 0.5) / width.
    const double x = reduce(static_cast<double>(uv.x) * mWidth - 0.5, mWidth, mWrapS);
    const double y = reduce(static_cast<double>(uv.y) * mHeight - 0.5, mHeight, mWrapT);
    const double fx0 = std::floor(x);
    const double fy0 = std::floor(y);
    const auto fx = static_cast<float>(x - fx0);
    const auto fy = static_cast<float>(y - fy0);
    const int x0 = static_cast<int>(fx0);
    const int y0 = static_cast<int>(fy0);
    const int xa = wrapIndex(x0, mWidth, mWrapS);
    const int xb = wrapIndex(x0 + 1, mWidth, mWrapS);
    const int ya = wrapIndex(y0, mHeight, mWrapT);
    const int yb = wrapIndex(y0 + 1, mHeight, mWrapT);
    const glm::vec4 top = glm::mix(texel(xa, ya), texel(xb, ya), fx);
    const glm::vec4 bottom = glm::mix(texel(xa, yb), texel(xb, yb), fx);
    return glm::mix(top, bottom, fy);
}

} // namespace ff::builder
