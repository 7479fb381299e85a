#pragma once

#include <glm/glm.hpp>

#include <cstdint>

namespace ff::builder {

/** Bit i of a 21-bit value moved to bit 3i (the classic magic numbers; each mask keeps only
 *  the copies that belong where they landed). */
constexpr std::uint64_t spreadBits(std::uint64_t v) noexcept {
    v &= 0x1FFFFFull;
    v = (v | (v << 32)) & 0x001F00000000FFFFull;
    v = (v | (v << 16)) & 0x001F0000FF0000FFull;
    v = (v | (v << 8)) & 0x100F00F00F00F00Full;
    v = (v | (v << 4)) & 0x10C30C30C30C30C3ull;
    v = (v | (v << 2)) & 0x1249249249249249ull;
    return v;
}

/** The Morton key of a cell of a grid of up to 2^21 cells an axis (bit order: x, y, z), so
 *  the cells of an aligned power-of-two block are one run of keys in octant order. */
constexpr std::uint64_t mortonKey(const glm::uvec3& cell) noexcept {
    return spreadBits(cell.x) | (spreadBits(cell.y) << 1) | (spreadBits(cell.z) << 2);
}

} // namespace ff::builder
