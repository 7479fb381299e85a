#pragma once

#include <ff/runtime/Selection.h>

#include <glm/glm.hpp>

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace ff::runtime {

/** A run of one Geometry page's items, drawn with transforms[transform]: triangle slots of a
 *  format 1 page (PackedTriangle), or whole clusters of a format 2 page as the cache keeps it,
 *  encoded behind its cluster table (runtime/src/CachedClusterPage.h). Carries the page's bytes:
 *  format 1's are uploaded as they are; format 2's say where each cluster's vertices and indices
 *  lie, which come decoded from the renderer's IDecodedGeometry. */
struct GeometryDraw {
    std::uint64_t page;       ///< the GPU arena's key
    const std::byte* payload; ///< the page's payload as resident, valid this frame
    std::uint32_t first;      ///< first triangle slot (format 1) or cluster (format 2)
    std::uint32_t count;      ///< triangle slots or clusters
    std::uint32_t transform;
    std::uint32_t triangles;    ///< the triangles the run draws (format 1: `count`)
    std::uint32_t payloadBytes; ///< the bytes `payload` spans
    /** The diameter in pixels its point clusters (splats) are drawn at: twice their error on
     *  screen at their cell's nearest point, at least 1 (0: the list's SplatStyle::pixels). */
    float pointPixels = 0.0f;
};

/** A color cube: a box in its transform's frame with six premultiplied RGBA8 faces. */
struct CubeDraw {
    glm::vec3 boxMin;
    glm::vec3 boxMax;
    std::uint32_t transform;
    std::array<std::array<std::uint8_t, 4>, 6> faces;
};

/**
 * What one batch of a frame draws: opaque geometry (any order) and color cubes in back-to-front
 * order. A traversal fills it up to FrameBudgets::drawBatchBytes and hands it to an IDrawSink;
 * reused from batch to batch (cleared, not freed) so traversal does not allocate.
 */
struct DrawList {
    std::vector<glm::mat4> transforms; ///< [0] is the identity
    /** The eye in each transform's local frame (cube face selection). */
    std::vector<glm::vec3> localEyes;
    std::vector<GeometryDraw> geometry;
    std::vector<CubeDraw> cubes;
    /** Draw the cubes as area-weighted points (each covers at most a few pixels) rather than as faces. */
    bool cubesAsPoints = false;
    /** The cubes are occluders (OcclusionOptions::cubesOcclude): drawn to depth only, where the
     *  opacity accumulated over a pixel reaches the frame's threshold, not in color. */
    bool cubesOcclude = false;
    /** How the point clusters among `geometry` (splats) are drawn. */
    SplatStyle splats;

    /** Bytes the entries take now (what FrameBudgets::drawBatchBytes bounds). */
    std::size_t bytes() const noexcept {
        return transforms.size() * (sizeof(glm::mat4) + sizeof(glm::vec3)) + geometry.size() * sizeof(GeometryDraw) +
               cubes.size() * sizeof(CubeDraw);
    }

    void clear() {
        transforms.clear();
        localEyes.clear();
        geometry.clear();
        cubes.clear();
    }
};

} // namespace ff::runtime
