#include "SubtreeEncoder.h"

#include <ff/storage/Assert.h>

#include <algorithm>
#include <cstring>
#include <span>

namespace ff::builder {

namespace {

storage::NodeRecord toRecord(const BuildNode& node) {
    storage::NodeRecord r{};
    r.cellMin = {node.cellMin.x, node.cellMin.y, node.cellMin.z};
    r.cellMax = {node.cellMax.x, node.cellMax.y, node.cellMax.z};
    r.boundsMin = {node.boundsMin.x, node.boundsMin.y, node.boundsMin.z};
    r.boundsMax = {node.boundsMax.x, node.boundsMax.y, node.boundsMax.z};
    r.cube = quantizeCube(node.cube);
    r.childCount = static_cast<std::uint8_t>(node.childCount);
    r.kind = node.kind;
    r.level = node.level;
    r.flags = storage::kNodeHasCube;
    if (node.octreeChildren)
        r.flags = static_cast<std::uint8_t>(r.flags | storage::kNodeOctreeChildren);
    if (node.kind == static_cast<std::uint8_t>(storage::NodeKind::Instance))
        r.geometryPage = node.instanceIndex;
    return r;
}

/** Shifts the relative page numbers of a Cell record (an Instance's geometryPage is an index). */
void relocateRecord(storage::NodeRecord& record, std::uint64_t geometryBase, std::uint64_t nodeBase, const EncodedSubtree::Slot& slot) {
    if (record.kind != static_cast<std::uint8_t>(storage::NodeKind::Cell))
        return;
    if (!slot.childrenPlacedElsewhere && record.childCount > 0)
        record.firstChild.page += static_cast<std::uint32_t>(nodeBase);
    if (!slot.trianglesPlacedElsewhere && record.geometryCount > 0)
        record.geometryPage += static_cast<std::uint32_t>(geometryBase);
}

// Triangles arrive in depth-first order (a node's own triangles, then its children's). They are
// written in the nodes' breadth-first order instead, the order of the node pages: a node's
// triangles are drawn when the node is visited and at least ε pixels large (a leaf draws
// them, an inner node draws its large triangles and refines), the same test at the same level
// for neighbours, so the geometry a cut needs is the levels above it, contiguous. Depth-first,
// a leaf that stopped a level early (large on screen) shares its page with the deeper leaves
// around it, which the frame does not draw: 1% of the geometry bytes used at 16 M triangles
// (docs/results/paging.md). Permutes in place through a 4-byte destination index per triangle,
// within the builder's per-triangle memory plan; a subtree of 2^32 triangles or more keeps
// depth-first order (false).
bool orderGeometryBreadthFirst(
        std::vector<BuildNode>& nodes,
        std::span<const std::uint32_t> breadthFirst,
        std::vector<storage::PackedTriangle>& triangles) {
    if (triangles.size() >= 0xFFFFFFFFull)
        return false;
    std::vector<std::uint32_t> destination(triangles.size());
    std::uint64_t cursor = 0;
    for (const std::uint32_t n : breadthFirst) {
        BuildNode& node = nodes[n];
        if (node.triangleCount == 0 || node.placedTriangles)
            continue;
        for (std::uint64_t k = 0; k < node.triangleCount; ++k)
            destination[node.firstTriangle + k] = static_cast<std::uint32_t>(cursor + k);
        node.firstTriangle = cursor;
        cursor += node.triangleCount;
    }
    FF_ASSERT(cursor == triangles.size()); // every triangle belongs to exactly one node
    for (std::size_t i = 0; i < triangles.size(); ++i) {
        while (destination[i] != i) {
            const std::uint32_t j = destination[i];
            std::swap(triangles[i], triangles[j]);
            std::swap(destination[i], destination[j]);
        }
    }
    return true;
}

} // namespace

std::uint64_t EncodedSubtree::geometryPageCount(std::uint32_t pageSize) const {
    const std::uint64_t perPage = storage::trianglesPerPage(pageSize);
    return (triangles.size() + perPage - 1) / perPage;
}

EncodedSubtree encodeSubtree(
        std::vector<BuildNode> nodes,
        std::vector<storage::PackedTriangle> triangles,
        std::uint32_t pageSize,
        CrownBudget crownBudget) {
    FF_ASSERT(!nodes.empty());
    const std::uint32_t perPage = storage::nodesPerPage(pageSize);
    const std::uint32_t trianglesPerPage = storage::trianglesPerPage(pageSize);

    // Breadth-first order of the whole subtree, each node once; levelEnd[d] is where level d
    // ends in it.
    std::vector<std::uint32_t> order; // node indices
    order.reserve(nodes.size());
    order.push_back(0);
    std::vector<std::size_t> levelEnd;
    for (std::size_t begin = 0; begin < order.size();) {
        const std::size_t end = order.size();
        for (std::size_t i = begin; i < end; ++i) {
            const BuildNode& node = nodes[order[i]];
            if (node.placedChildren)
                continue;
            for (std::uint32_t c = 0; c < node.childCount; ++c)
                order.push_back(node.firstChild + c);
        }
        levelEnd.push_back(end);
        begin = end;
    }
    // The crown: the root and the whole levels below it that fit the budget. Its lowest level
    // starts at crownLowest in `order`; the children of that level and of every level below
    // are placed here.
    std::size_t crownSize = 0;
    std::size_t crownLowest = 0;
    for (std::size_t d = 0; d < levelEnd.size() && crownBudget.nodes > 0; ++d) {
        if (d > 0 && levelEnd[d] > crownBudget.nodes)
            break;
        crownLowest = d == 0 ? 0 : levelEnd[d - 1];
        crownSize = levelEnd[d];
    }

    // Pages fill with whole sibling blocks in breadth-first order: level by level, and within a
    // level in octant (Morton) order, so a page holds one level of one neighbourhood. A frame's
    // cut runs through the hierarchy at about one level per neighbourhood and refines every
    // node above it, so the pages it needs are the levels down to the cut and hold few records
    // it does not use; treelets (a subtree per page, several levels deep) would bring in the
    // levels below the cut with them (measured in docs/results/paging.md: 22% of the node bytes
    // used at 64 M triangles, against ~90%).
    struct Placement {
        std::uint32_t page = 0;
        std::uint32_t slot = 0;
    };
    std::vector<Placement> placement(nodes.size());
    std::vector<std::vector<std::uint32_t>> pages; // node indices per page
    auto placeBlock = [&](std::uint32_t first, std::uint32_t count) {
        FF_ASSERT(count <= perPage);
        if (pages.empty() || pages.back().size() + count > perPage)
            pages.emplace_back();
        auto& page = pages.back();
        for (std::uint32_t i = 0; i < count; ++i) {
            placement[first + i] = {static_cast<std::uint32_t>(pages.size() - 1), static_cast<std::uint32_t>(page.size())};
            page.push_back(first + i);
        }
    };
    if (crownSize == 0)
        placeBlock(0, 1);
    for (std::size_t i = crownLowest; i < order.size(); ++i) {
        const BuildNode& node = nodes[order[i]];
        if (node.childCount > 0 && !node.placedChildren)
            placeBlock(node.firstChild, node.childCount);
    }

    EncodedSubtree out;
    const bool ordered = orderGeometryBreadthFirst(nodes, order, triangles);
    // Crown nodes come first in breadth-first order, and so do their triangles: the first
    // `crownSpan`. Those that fit the budget move to crownTriangles, in the same order; the
    // others close up at the front and stay with the subtree (placedTriangles).
    std::uint64_t crownSpan = 0;
    for (std::size_t i = 0; i < crownSize; ++i)
        crownSpan += nodes[order[i]].triangleCount;
    FF_ASSERT(ordered || crownSpan == 0); // a crown comes from a chunk, far below 2^32 triangles
    std::uint64_t kept = 0;
    std::vector<bool> keptInSubtree(crownSize, false);
    for (std::size_t i = 0; i < crownSize; ++i) {
        BuildNode& node = nodes[order[i]];
        if (node.triangleCount == 0)
            continue;
        const auto first = triangles.begin() + static_cast<std::ptrdiff_t>(node.firstTriangle);
        const auto last = first + static_cast<std::ptrdiff_t>(node.triangleCount);
        if (out.crownTriangles.size() + node.triangleCount <= crownBudget.triangles) {
            node.firstTriangle = out.crownTriangles.size();
            out.crownTriangles.insert(out.crownTriangles.end(), first, last);
        } else {
            if (kept != node.firstTriangle) // kept < firstTriangle: a move to the front
                std::move(first, last, triangles.begin() + static_cast<std::ptrdiff_t>(kept));
            node.firstTriangle = kept;
            kept += node.triangleCount;
            keptInSubtree[i] = true;
        }
    }
    const std::uint64_t moved = crownSpan - kept;
    triangles.erase(triangles.begin() + static_cast<std::ptrdiff_t>(kept), triangles.begin() + static_cast<std::ptrdiff_t>(crownSpan));
    auto runStart = [&](std::uint64_t firstTriangle) {
        return TriangleSlot{static_cast<std::uint32_t>(firstTriangle / trianglesPerPage),
                            static_cast<std::uint32_t>(firstTriangle % trianglesPerPage)};
    };

    auto recordOf = [&](std::uint32_t n) {
        const BuildNode& node = nodes[n];
        storage::NodeRecord r = toRecord(node);
        if (node.placedChildren)
            r.firstChild = *node.placedChildren;
        else if (node.childCount > 0)
            r.firstChild = {placement[node.firstChild].page, placement[node.firstChild].slot};
        if (node.triangleCount > 0 && node.kind == static_cast<std::uint8_t>(storage::NodeKind::Cell)) {
            const TriangleSlot start = node.placedTriangles ? *node.placedTriangles : runStart(node.firstTriangle - moved);
            r.geometryPage = start.page;
            r.geometryFirst = start.slot;
            r.geometryCount = static_cast<std::uint32_t>(node.triangleCount);
        }
        return r;
    };
    out.nodePages.resize(pages.size());
    for (std::size_t p = 0; p < pages.size(); ++p) {
        for (std::uint32_t n : pages[p]) {
            out.nodePages[p].push_back({recordOf(n), nodes[n].placedChildren.has_value(), nodes[n].placedTriangles.has_value()});
            ++out.nodeCount;
        }
    }
    for (const BuildNode& node : nodes)
        out.maxLevel = std::max<std::uint32_t>(out.maxLevel, node.level);

    // The crown, renumbered in breadth-first order: children follow in the order their parents
    // come, so a cursor over the positions after the root hands out each first child.
    out.crown.reserve(crownSize);
    std::size_t nextPosition = 1;
    for (std::size_t i = 0; i < crownSize; ++i) {
        BuildNode node = nodes[order[i]];
        FF_ASSERT(!node.placedChildren && !node.placedTriangles); // only the tree above the crowns has those
        if (keptInSubtree[i])
            node.placedTriangles = runStart(node.firstTriangle);
        if (node.childCount > 0 && i >= crownLowest) {
            node.placedChildren = storage::NodeRef{placement[node.firstChild].page, placement[node.firstChild].slot};
        } else if (node.childCount > 0) {
            node.firstChild = static_cast<std::uint32_t>(nextPosition);
            nextPosition += node.childCount;
        }
        out.crown.push_back(std::move(node));
    }
    if (crownSize == 0)
        out.rootRef = storage::NodeRef{0, 0};
    out.triangles = std::move(triangles);
    return out;
}

Status commitSubtree(storage::SceneWriter& writer, EncodedSubtree& subtree) {
    const std::uint32_t pageSize = writer.pageSize();
    const std::uint64_t perPage = storage::trianglesPerPage(pageSize);
    const std::uint64_t geometryBase = writer.nextPageIndex();
    const std::uint64_t geometryPages = subtree.geometryPageCount(pageSize);
    const std::uint64_t nodeBase = geometryBase + geometryPages;
    if (nodeBase + subtree.nodePages.size() > 0xFFFFFFFFull)
        return Status(ErrorCode::Unsupported, "scene needs more than 2^32 pages; use a larger --page-size");

    for (std::uint64_t p = 0; p < geometryPages; ++p) {
        const std::uint64_t first = p * perPage;
        const std::uint64_t count = std::min<std::uint64_t>(perPage, subtree.triangles.size() - first);
        const auto bytes = std::as_bytes(std::span(subtree.triangles).subspan(first, count));
        FF_RETURN_IF_ERROR(writer.appendPage(storage::PageType::Geometry, bytes).status());
    }
    std::vector<std::byte> buffer;
    for (auto& page : subtree.nodePages) {
        buffer.resize(page.size() * sizeof(storage::NodeRecord));
        for (std::size_t i = 0; i < page.size(); ++i) {
            storage::NodeRecord record = page[i].record;
            relocateRecord(record, geometryBase, nodeBase, page[i]);
            std::memcpy(buffer.data() + i * sizeof(storage::NodeRecord), &record, sizeof(record));
        }
        FF_RETURN_IF_ERROR(writer.appendPage(storage::PageType::Nodes, buffer).status());
    }
    for (BuildNode& node : subtree.crown) {
        if (node.placedChildren)
            node.placedChildren->page += static_cast<std::uint32_t>(nodeBase);
        if (node.placedTriangles)
            node.placedTriangles->page += static_cast<std::uint32_t>(geometryBase);
    }
    if (subtree.rootRef)
        subtree.rootRef->page += static_cast<std::uint32_t>(nodeBase);
    // Free the memory, not just the elements: `= {}` picks operator=(initializer_list), which
    // keeps the capacity, and every committed chunk would stay resident until the build ends.
    subtree.triangles = std::vector<storage::PackedTriangle>();
    subtree.nodePages = std::vector<std::vector<EncodedSubtree::Slot>>();
    return Status::ok();
}

} // namespace ff::builder
