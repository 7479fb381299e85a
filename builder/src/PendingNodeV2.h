#pragma once

#include <array>
#include <cstdint>

namespace ff::builder {

/** A v2 record waiting in a level region's spill file (LevelRegionsV2): its fields, its
 *  references local to the regions. */
struct PendingNodeV2 {
    std::array<float, 3> boundsMin;
    std::array<float, 3> boundsMax;
    std::array<float, 3> cellMin; ///< the box its cube was baked over
    std::array<float, 3> cellMax;
    std::array<std::array<std::uint8_t, 4>, 6> cube;
    std::uint32_t firstChild;          ///< position in the next level's region
    std::uint32_t firstRepresentation; ///< in its region's representations
    float drawnTriangles;              ///< own and below, as stored
    std::uint8_t childCount;
    std::uint8_t representationCount;
    std::uint8_t flags; ///< storage::NodeFlagsV2
    std::uint8_t reserved;
};
static_assert(sizeof(PendingNodeV2) == 88);

} // namespace ff::builder
