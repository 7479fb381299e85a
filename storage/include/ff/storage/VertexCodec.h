#pragma once

// Encoding of the PackedVertex fields: octahedral unit normals in snorm16 and sRGB8 colour.
// The renderer's vertex shader decodes the same way (runtime/src/gl/Shaders.cpp).

#include <array>
#include <cstdint>

namespace ff::storage {

/** Octahedral encoding of a direction; (0,0,0) or non-finite input encodes +Z. */
std::array<std::int16_t, 2> encodeOctNormal(float x, float y, float z) noexcept;

/** Decodes to a unit vector. */
std::array<float, 3> decodeOctNormal(std::array<std::int16_t, 2> oct) noexcept;

/**
 * The octahedral code of an unlit vertex (glTF KHR_materials_unlit): drawn with its colour as it
 * is, light factor 1, in every representation. encodeOctNormal never writes it (its snorm16
 * values stay within ±32767), so the code is free; decodeOctNormal still reads it as a unit
 * vector, for readers that do not know it. Format v1 has no other room for the bit.
 */
inline constexpr std::array<std::int16_t, 2> kUnlitNormalOct = {-32768, -32768};

/** True for kUnlitNormalOct. */
constexpr bool isUnlitNormal(std::array<std::int16_t, 2> oct) noexcept { return oct == kUnlitNormalOct; }

/** Linear [0,1] (clamped; NaN -> 0) to the nearest sRGB8 code. */
std::uint8_t linearToSrgb8(float linear) noexcept;

/** sRGB8 code to linear [0,1] (exact table). */
float srgb8ToLinear(std::uint8_t code) noexcept;

/** Linear [0,1] (clamped; NaN -> 0) to unorm8, rounded to nearest. */
std::uint8_t toUnorm8(float value) noexcept;

} // namespace ff::storage
