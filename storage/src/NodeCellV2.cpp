#include <ff/storage/NodeCellV2.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

namespace ff::storage {

NodeBox octantCell(const NodeBox& cell, std::uint8_t octant) noexcept {
    NodeBox out;
    for (std::size_t a = 0; a < 3; ++a) {
        const float mid = cell.min[a] + 0.5f * (cell.max[a] - cell.min[a]);
        const bool upper = (static_cast<unsigned>(octant) >> a & 1u) != 0;
        out.min[a] = upper ? mid : cell.min[a];
        out.max[a] = upper ? cell.max[a] : mid;
    }
    return out;
}

float rootCellEdge(const std::array<float, 3>& size) noexcept {
    const float edge = std::max({size[0], size[1], size[2]});
    return edge * (1.0f + 1e-5f) + std::numeric_limits<float>::min();
}

NodeBox rootParentCell(const NodeBox& hierarchy) noexcept {
    const float edge = rootCellEdge(
            {hierarchy.max[0] - hierarchy.min[0],
             hierarchy.max[1] - hierarchy.min[1],
             hierarchy.max[2] - hierarchy.min[2]});
    NodeBox out;
    for (std::size_t a = 0; a < 3; ++a) {
        out.min[a] = hierarchy.min[a];
        out.max[a] = hierarchy.min[a] + 2.0f * edge;
    }
    return out;
}

DecodedNodeV2 rootParentV2(const NodeBox& hierarchy) noexcept {
    return {hierarchy, rootParentCell(hierarchy)};
}

NodeBox cellOfNode(const NodeV2& node, const NodeBox& parentCell) noexcept {
    return (node.flags & kNodeV2OctantCell) != 0 ? octantCell(parentCell, node.octant) : node.bounds;
}

std::optional<std::uint8_t> matchingOctant(const NodeBox& cell, const NodeBox& parentCell) noexcept {
    std::uint8_t octant = 0;
    for (std::size_t a = 0; a < 3; ++a) {
        if (!(parentCell.max[a] > parentCell.min[a]) || !std::isfinite(parentCell.max[a] - parentCell.min[a]))
            return std::nullopt;
        const float mid = parentCell.min[a] + 0.5f * (parentCell.max[a] - parentCell.min[a]);
        if (0.5f * (cell.min[a] + cell.max[a]) >= mid)
            octant = static_cast<std::uint8_t>(octant | 1u << a);
    }
    const NodeBox derived = octantCell(parentCell, octant);
    for (std::size_t a = 0; a < 3; ++a) {
        const float side = derived.max[a] - derived.min[a];
        const float magnitude = std::max({std::abs(derived.min[a]), std::abs(derived.max[a])});
        const float tolerance =
                std::max(1e-3f * side, 4.0f * std::numeric_limits<float>::epsilon() * magnitude);
        if (!(std::abs(derived.min[a] - cell.min[a]) <= tolerance) ||
            !(std::abs(derived.max[a] - cell.max[a]) <= tolerance))
            return std::nullopt;
    }
    return octant;
}

} // namespace ff::storage
