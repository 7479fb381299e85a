#include "LeafCollapse.h"

#include "Permutation.h"

#include <ff/storage/Assert.h>

#include <limits>

namespace ff::builder {

namespace {

constexpr std::uint64_t kPlacedElsewhere = std::numeric_limits<std::uint64_t>::max();

bool placedElsewhere(const BuildNode& node) {
    return node.placedChildren.has_value() || node.placedTriangles.has_value();
}

} // namespace

std::uint64_t collapseSmallSubtrees(
        std::vector<BuildNode>& nodes,
        std::span<storage::PackedTriangle> triangles,
        std::uint64_t leafTriangles) {
    if (nodes.empty() || leafTriangles == 0)
        return 0;
    // Triangles below each node, saturated where a payload lives elsewhere (never collapsed).
    std::vector<std::uint64_t> below(nodes.size(), 0);
    for (std::size_t n = nodes.size(); n-- > 0;) {
        const BuildNode& node = nodes[n];
        if (placedElsewhere(node)) {
            below[n] = kPlacedElsewhere;
            continue;
        }
        below[n] = node.triangleCount;
        for (std::uint32_t c = 0; c < node.childCount; ++c) {
            FF_ASSERT(node.firstChild + c > n); // children after parents
            const std::uint64_t child = below[node.firstChild + c];
            below[n] = child == kPlacedElsewhere ? kPlacedElsewhere : below[n] + child;
        }
    }

    // Depth-first order of every reachable run: a collapsed subtree's triangles are then
    // contiguous, starting with its root's own.
    FF_ASSERT(triangles.size() < 0xFFFFFFFFull); // a chunk's, or a prototype within one chunk
    std::vector<std::uint32_t> destination(triangles.size(), 0);
    std::vector<std::uint64_t> newFirst(nodes.size(), 0);
    std::vector<bool> collapse(nodes.size(), false);
    std::uint64_t cursor = 0;
    std::uint64_t collapsed = 0;
    std::vector<std::uint32_t> stack{0};
    while (!stack.empty()) {
        const std::uint32_t n = stack.back();
        stack.pop_back();
        const BuildNode& node = nodes[n];
        if (!node.placedTriangles) {
            for (std::uint64_t k = 0; k < node.triangleCount; ++k)
                destination[node.firstTriangle + k] = static_cast<std::uint32_t>(cursor + k);
            newFirst[n] = cursor;
            cursor += node.triangleCount;
        }
        if (node.placedChildren)
            continue;
        collapse[n] = node.childCount > 0 && below[n] <= leafTriangles &&
                      node.kind == static_cast<std::uint8_t>(storage::NodeKind::Cell);
        for (std::uint32_t c = node.childCount; c-- > 0;)
            stack.push_back(node.firstChild + c);
    }
    FF_ASSERT(cursor == triangles.size()); // every triangle belongs to exactly one node
    permuteInPlace(std::span(triangles), destination);
    // Outermost first: a collapsed node's descendants are unreachable, whatever they were.
    stack.assign(1, 0);
    while (!stack.empty()) {
        const std::uint32_t n = stack.back();
        stack.pop_back();
        BuildNode& node = nodes[n];
        if (!node.placedTriangles)
            node.firstTriangle = newFirst[n];
        if (collapse[n]) {
            ++collapsed;
            node.triangleCount = below[n];
            node.childCount = 0;
            node.octreeChildren = false;
            continue;
        }
        if (node.placedChildren)
            continue;
        for (std::uint32_t c = 0; c < node.childCount; ++c)
            stack.push_back(node.firstChild + c);
    }
    return collapsed;
}

} // namespace ff::builder
