#include "SubtreeEncoder.h"

#include "Permutation.h"

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
    permuteInPlace(std::span(triangles), destination);
    return true;
}

/** The subtree in breadth-first order, each node once; levelEnd[d] is where depth d ends in it. */
struct BreadthFirst {
    std::vector<std::uint32_t> order; ///< node indices
    std::vector<std::size_t> levelEnd;
};

BreadthFirst breadthFirst(const std::vector<BuildNode>& nodes) {
    BreadthFirst out;
    out.order.reserve(nodes.size());
    out.order.push_back(0);
    for (std::size_t begin = 0; begin < out.order.size();) {
        const std::size_t end = out.order.size();
        for (std::size_t i = begin; i < end; ++i) {
            const BuildNode& node = nodes[out.order[i]];
            if (node.placedChildren)
                continue;
            for (std::uint32_t c = 0; c < node.childCount; ++c)
                out.order.push_back(node.firstChild + c);
        }
        out.levelEnd.push_back(end);
        begin = end;
    }
    return out;
}

} // namespace

std::uint64_t EncodedSubtree::geometryPageCount(std::uint32_t pageSize) const {
    const std::uint64_t perPage = storage::trianglesPerPage(pageSize);
    return (triangles.size() + perPage - 1) / perPage;
}

EncodedSubtree encodeSubtree(
        std::vector<BuildNode> nodes,
        std::vector<storage::PackedTriangle> triangles,
        std::uint32_t pageSize) {
    FF_ASSERT(!nodes.empty());
    const std::uint32_t perPage = storage::nodesPerPage(pageSize);
    const std::uint32_t trianglesPerPage = storage::trianglesPerPage(pageSize);
    const BreadthFirst bf = breadthFirst(nodes);

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
    placeBlock(0, 1);
    for (const std::uint32_t n : bf.order) {
        const BuildNode& node = nodes[n];
        if (node.childCount > 0 && !node.placedChildren)
            placeBlock(node.firstChild, node.childCount);
    }

    orderGeometryBreadthFirst(nodes, bf.order, triangles);
    auto recordOf = [&](std::uint32_t n) {
        const BuildNode& node = nodes[n];
        storage::NodeRecord r = toRecord(node);
        if (node.placedChildren)
            r.firstChild = *node.placedChildren;
        else if (node.childCount > 0)
            r.firstChild = {placement[node.firstChild].page, placement[node.firstChild].slot};
        if (node.triangleCount > 0 && node.kind == static_cast<std::uint8_t>(storage::NodeKind::Cell)) {
            const TriangleSlot start = node.placedTriangles
                    ? *node.placedTriangles
                    : TriangleSlot{static_cast<std::uint32_t>(node.firstTriangle / trianglesPerPage),
                                   static_cast<std::uint32_t>(node.firstTriangle % trianglesPerPage)};
            r.geometryPage = start.page;
            r.geometryFirst = start.slot;
            r.geometryCount = static_cast<std::uint32_t>(node.triangleCount);
        }
        return r;
    };
    EncodedSubtree out;
    out.nodePages.resize(pages.size());
    for (std::size_t p = 0; p < pages.size(); ++p) {
        for (std::uint32_t n : pages[p]) {
            out.nodePages[p].push_back({recordOf(n), nodes[n].placedChildren.has_value(), nodes[n].placedTriangles.has_value()});
            ++out.nodeCount;
        }
    }
    for (const BuildNode& node : nodes)
        out.maxLevel = std::max<std::uint32_t>(out.maxLevel, node.level);
    out.triangles = std::move(triangles);
    return out;
}

LevelledSubtree encodeLevels(
        std::vector<BuildNode> nodes,
        std::vector<storage::PackedTriangle> triangles,
        std::vector<std::optional<StandIn>> standIns) {
    FF_ASSERT(!nodes.empty());
    FF_ASSERT(standIns.empty() || standIns.size() == nodes.size());
    const BreadthFirst bf = breadthFirst(nodes);
    const bool ordered = orderGeometryBreadthFirst(nodes, bf.order, triangles);
    FF_ASSERT(ordered); // PrototypeBuilder keeps chunks below 2^32 triangles

    LevelledSubtree out;
    const std::size_t depths = bf.levelEnd.size();
    out.rootLevel = nodes[0].level;
    out.levels.resize(depths);

    // Where each node sits in the order, and at which depth.
    std::vector<std::uint32_t> position(nodes.size());
    std::vector<std::size_t> depthOf(bf.order.size());
    for (std::size_t d = 0, i = 0; d < depths; ++d)
        for (; i < bf.levelEnd[d]; ++i) {
            position[bf.order[i]] = static_cast<std::uint32_t>(i);
            depthOf[i] = d;
        }
    // The triangles are in breadth-first order, hence level by level: each level's share is a
    // range of `triangles`, and a node's local offset is where its run starts in that range.
    std::vector<std::uint64_t> levelTriangles(depths + 1, 0);
    for (std::size_t i = 0; i < bf.order.size(); ++i)
        levelTriangles[depthOf[i] + 1] += nodes[bf.order[i]].triangleCount;
    for (std::size_t d = 0; d < depths; ++d) {
        levelTriangles[d + 1] += levelTriangles[d];
        out.levels[d].triangleBegin = levelTriangles[d];
        out.levels[d].triangleCount = levelTriangles[d + 1] - levelTriangles[d];
    }
    auto localTriangle = [&](std::size_t i) {
        return nodes[bf.order[i]].firstTriangle - levelTriangles[depthOf[i]];
    };

    // The root is kept back; every other record goes to its level, and the sibling blocks
    // follow the breadth-first order, the root's first.
    out.root = nodes[0];
    if (!standIns.empty())
        out.rootStandIn = std::move(standIns[0]);
    if (out.root.childCount > 0) {
        out.levels[1].blocks.push_back(static_cast<std::uint8_t>(out.root.childCount));
        const auto first = position[out.root.firstChild] - static_cast<std::uint32_t>(bf.levelEnd[0]);
        out.root.placedChildren = storage::NodeRef{0, first};
    }
    if (out.root.triangleCount > 0)
        out.root.placedTriangles = TriangleSlot{0, static_cast<std::uint32_t>(localTriangle(0))};
    for (std::size_t i = 1; i < bf.order.size(); ++i) {
        const BuildNode& node = nodes[bf.order[i]];
        const std::size_t d = depthOf[i];
        storage::NodeRecord r = toRecord(node);
        if (node.childCount > 0) {
            r.firstChild = {0, position[node.firstChild] - static_cast<std::uint32_t>(bf.levelEnd[d])};
            out.levels[d + 1].blocks.push_back(static_cast<std::uint8_t>(node.childCount));
        }
        if (node.triangleCount > 0) {
            r.geometryFirst = static_cast<std::uint32_t>(localTriangle(i));
            r.geometryCount = static_cast<std::uint32_t>(node.triangleCount);
        }
        out.levels[d].records.push_back(r);
        if (!standIns.empty()) {
            out.levels[d].standIns.resize(out.levels[d].records.size() - 1);
            out.levels[d].standIns.push_back(std::move(standIns[bf.order[i]]));
        }
        ++out.nodeCount;
    }
    for (const BuildNode& node : nodes)
        out.maxLevel = std::max<std::uint32_t>(out.maxLevel, node.level);
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
    subtree.rootRef.page += static_cast<std::uint32_t>(nodeBase);
    // Free the memory, not just the elements: `= {}` picks operator=(initializer_list), which
    // keeps the capacity, and every committed chunk would stay resident until the build ends.
    subtree.triangles = std::vector<storage::PackedTriangle>();
    subtree.nodePages = std::vector<std::vector<EncodedSubtree::Slot>>();
    return Status::ok();
}

} // namespace ff::builder
