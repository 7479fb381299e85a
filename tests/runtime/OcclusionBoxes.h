#pragma once

#include <ff/runtime/Traversal.h>

#include <glm/glm.hpp>

#include <cstddef>

namespace ff::runtime::test {

/** The box [centre - half, centre + half] with its corners in the order the occlusion testers
 *  expect (corner i takes the high side of axis a where bit a of i is set). */
inline OcclusionBox boxAround(const glm::vec3& centre, float half) {
    OcclusionBox box;
    for (int i = 0; i < 8; ++i)
        box.corners[static_cast<std::size_t>(i)] =
                centre + half * glm::vec3((i & 1) ? 1.0f : -1.0f, (i & 2) ? 1.0f : -1.0f, (i & 4) ? 1.0f : -1.0f);
    return box;
}

} // namespace ff::runtime::test
