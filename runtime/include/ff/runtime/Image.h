#pragma once

#include <glm/glm.hpp>

#include <cstdint>
#include <vector>

namespace ff::runtime {

/**
 * A rendered frame: sRGB8 colour already composited over the background, plus coverage
 * (alpha: 0 where only background shows, 255 where the scene covers the pixel). Row 0 is the
 * top row.
 */
struct Image {
    int width = 0;
    int height = 0;
    std::vector<std::uint8_t> rgba; ///< width * height * 4

    std::uint8_t* pixel(int x, int y) { return &rgba[(static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x)) * 4]; }
    const std::uint8_t* pixel(int x, int y) const { return &rgba[(static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x)) * 4]; }
};

/**
 * Averages factor x factor blocks of a framebuffer read back bottom-up (premultiplied linear
 * colour stored sRGB-encoded, linear alpha) in linear space and composites the result over
 * `backgroundLinear`. `samples` is (width*factor) x (height*factor) RGBA8.
 */
Image resolveFramebuffer(const std::vector<std::uint8_t>& samples, int width, int height, int factor,
                         const glm::vec3& backgroundLinear);

} // namespace ff::runtime
