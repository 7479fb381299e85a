#pragma once

// How far a stand-in's shading may be off (StandIns.h). meshoptimizer 0.18 simplifies by
// position alone, and its error says how far the surface moved, not how its colours and normals
// did: a stand-in of a scanned skull whose surface moved a hundredth of a pixel still showed its
// large triangles in the shading (9 dB below brute force at 1.2 radii). This measures it.

#include <ff/storage/SceneFormat.h>

#include <span>

namespace ff::builder {

/** A colour difference of this many 8-bit steps (sRGB as displayed, or alpha) or more counts
 *  in full; and so does a normal turned by kShadingNormalStepDegrees. Chosen on the 4 M terrain
 *  and the scanned skull at 640 x 480, ε = 1 (1.2, 2.5 and 6 radii), against brute force: at
 *  8 steps and 10° the terrain's view at 2.5 radii was 3.5 x faster, at 16 and 20° 6.6 x, at 32
 *  and 30° 8.6 x with the skull at most 0.7 dB below brute force, at 64 and 45° 9.2 x with the
 *  skull 1.4 dB below; position alone (meshoptimizer's error) 11.7 x, the skull 9.4 dB below. */
inline constexpr float kShadingColourStep = 32.0f;
inline constexpr float kShadingNormalStepDegrees = 30.0f;

/** How differently two vertices shade, from 0 (alike) to 1 (a colour or normal step apart, or
 *  one lit and one unlit). */
[[nodiscard]] float shadingDifference(const storage::PackedVertex& a, const storage::PackedVertex& b);

/**
 * The shading error of `kept` (a simplification of the triangles `source`; both index
 * `vertices`), in the vertices' units: for every vertex of the source the simplification
 * removed, the shading the stand-in interpolates at its nearest point (barycentric, colours and
 * normals) against the vertex's own (shadingDifference), times how far the vertex lies from the
 * nearest corner of that triangle: a colour edge or a crease's shading can drift that far. The
 * largest over the removed vertices; 0 when none was removed. A smooth gradient or a smooth
 * surface's normals interpolate well and add little.
 */
[[nodiscard]] float shadingError(
        std::span<const storage::PackedVertex> vertices,
        std::span<const unsigned> source,
        std::span<const unsigned> kept);

} // namespace ff::builder
