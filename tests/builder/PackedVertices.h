#pragma once

// Vertices for builder tests that lay out sheets by hand.

#include <ff/storage/SceneFormat.h>
#include <ff/storage/VertexCodec.h>

#include <array>
#include <cstdint>

namespace ff::builder::testing {

/** A vertex at (x, y, z) of `color`, its normal up (+y): a point of a horizontal sheet. */
inline storage::PackedVertex upFacingVertex(float x, float y, float z, std::array<std::uint8_t, 4> color) {
    storage::PackedVertex v;
    v.position = {x, y, z};
    v.normalOct = storage::encodeOctNormal(0.0f, 1.0f, 0.0f);
    v.color = color;
    return v;
}

} // namespace ff::builder::testing
