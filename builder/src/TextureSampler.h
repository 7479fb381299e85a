#pragma once

// Base-colour textures for vertex colouring: decoded once to RGBA8, sampled bilinearly in
// linear space (texels are sRGB-decoded before filtering) with glTF's wrap modes.

#include <ff/storage/Status.h>

#include <glm/glm.hpp>

#include <cstdint>
#include <span>
#include <vector>

namespace ff::builder {

enum class WrapMode { Repeat, ClampToEdge, MirroredRepeat };

/** glTF sampler wrap constant (10497, 33071, 33648) to WrapMode; unknown values repeat. */
WrapMode wrapModeFromGltf(int wrap) noexcept;

/** sRGB-encoded 8-bit value to linear [0,1]. */
float srgb8ToLinear(std::uint8_t value) noexcept;

class TextureSampler {
public:
    /** Decodes a PNG/JPEG (anything stb_image reads). Errors: InvalidInput. */
    [[nodiscard]] static Result<TextureSampler> decode(std::span<const unsigned char> encoded);

    /** Builds a texture from raw sRGB RGBA8 texels (row 0 = top, i.e. v = 0). */
    TextureSampler(int width, int height, std::vector<std::uint8_t> rgba, WrapMode s, WrapMode t);

    void setWrap(WrapMode s, WrapMode t) noexcept {
        mWrapS = s;
        mWrapT = t;
    }

    /** Linear RGBA at glTF texture coordinate `uv` (origin top-left), bilinear. Non-finite
     *  coordinates sample texel (0,0). */
    glm::vec4 sample(glm::vec2 uv) const noexcept;

    int width() const noexcept { return mWidth; }
    int height() const noexcept { return mHeight; }

private:
    glm::vec4 texel(int x, int y) const noexcept;

    int mWidth = 0;
    int mHeight = 0;
    std::vector<std::uint8_t> mRgba;
    WrapMode mWrapS = WrapMode::Repeat;
    WrapMode mWrapT = WrapMode::Repeat;
};

} // namespace ff::builder
