#include "SubtreeEncoder.h"

#include <ff/storage/Assert.h>

#include <cstring>
#include <deque>

namespace ff::builder {

namespace {

storage::NodeRecord toRecord(const BuildNode& node) {
    if (node.external)
        return *node.external;
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

bool isRelocatable(const storage::NodeRecord& r) {
    return r.kind == static_cast<std::uint8_t>(storage::NodeKind::Cell);
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
        bool placeRoot) {
    FF_ASSERT(!nodes.empty());
    const std::uint32_t perPage = storage::nodesPerPage(pageSize);
    const std::uint32_t trianglesPerPage = storage::trianglesPerPage(pageSize);

    struct Placement {
        std::uint32_t page = 0;
        std::uint32_t slot = 0;
    };
    std::vector<Placement> placement(nodes.size());
    std::vector<std::vector<std::uint32_t>> pages; // node indices per page

    auto placeBlock = [&](std::uint32_t first, std::uint32_t count) {
        auto& page = pages.back();
        for (std::uint32_t i = 0; i < count; ++i) {
            placement[first + i] = {static_cast<std::uint32_t>(pages.size() - 1), static_cast<std::uint32_t>(page.size())};
            page.push_back(first + i);
        }
    };

    // Pages fill breadth-first from sibling blocks, whole blocks only. A block that does not fit
    // the current page waits in `pending`; when the page's own subtree is exhausted the next
    // pending block continues in the same page if it fits, so small subtrees share pages
    // instead of each opening one.
    std::deque<std::uint32_t> pending; // nodes whose children block is not placed yet
    auto fits = [&](std::uint32_t count) { return pages.back().size() + count <= perPage; };
    auto fillFrom = [&](std::deque<std::uint32_t> local) {
        while (!local.empty()) {
            const std::uint32_t n = local.front();
            local.pop_front();
            const BuildNode& node = nodes[n];
            if (node.childCount == 0 || node.external)
                continue;
            FF_ASSERT(node.childCount <= perPage);
            if (!fits(node.childCount)) {
                pending.push_back(n);
                continue;
            }
            placeBlock(node.firstChild, node.childCount);
            for (std::uint32_t c = 0; c < node.childCount; ++c)
                local.push_back(node.firstChild + c);
        }
    };

    if (placeRoot) {
        pages.emplace_back();
        placeBlock(0, 1);
        fillFrom({0});
    } else if (nodes[0].childCount > 0) {
        pending.push_back(0);
    }
    while (!pending.empty()) {
        const std::uint32_t parent = pending.front();
        pending.pop_front();
        if (pages.empty() || !fits(nodes[parent].childCount))
            pages.emplace_back();
        fillFrom({parent});
    }

    EncodedSubtree out;
    auto recordOf = [&](std::uint32_t n) {
        const BuildNode& node = nodes[n];
        storage::NodeRecord r = toRecord(node);
        if (node.external)
            return r;
        if (node.childCount > 0) {
            const Placement& p = placement[node.firstChild];
            r.firstChild = {p.page, p.slot};
        }
        if (node.triangleCount > 0 && node.kind == static_cast<std::uint8_t>(storage::NodeKind::Cell)) {
            r.geometryPage = static_cast<std::uint32_t>(node.firstTriangle / trianglesPerPage);
            r.geometryFirst = static_cast<std::uint32_t>(node.firstTriangle % trianglesPerPage);
            r.geometryCount = static_cast<std::uint32_t>(node.triangleCount);
        }
        out.maxLevel = std::max<std::uint32_t>(out.maxLevel, r.level);
        return r;
    };
    out.nodePages.resize(pages.size());
    for (std::size_t p = 0; p < pages.size(); ++p) {
        for (std::uint32_t n : pages[p]) {
            out.nodePages[p].push_back({recordOf(n), nodes[n].external.has_value()});
            ++out.nodeCount;
        }
    }
    out.root = recordOf(0);
    if (placeRoot)
        out.rootRef = storage::NodeRef{0, 0};
    out.triangles = std::move(triangles);
    return out;
}

void relocateRecord(storage::NodeRecord& record, std::uint64_t geometryBase, std::uint64_t nodeBase) {
    if (!isRelocatable(record))
        return;
    if (record.childCount > 0)
        record.firstChild.page += static_cast<std::uint32_t>(nodeBase);
    if (record.geometryCount > 0)
        record.geometryPage += static_cast<std::uint32_t>(geometryBase);
}

Result<storage::NodeRecord> commitSubtree(storage::SceneWriter& writer, EncodedSubtree& subtree) {
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
            if (!page[i].absolute)
                relocateRecord(record, geometryBase, nodeBase);
            std::memcpy(buffer.data() + i * sizeof(storage::NodeRecord), &record, sizeof(record));
        }
        FF_RETURN_IF_ERROR(writer.appendPage(storage::PageType::Nodes, buffer).status());
    }
    storage::NodeRecord root = subtree.root;
    relocateRecord(root, geometryBase, nodeBase);
    if (subtree.rootRef)
        subtree.rootRef->page += static_cast<std::uint32_t>(nodeBase);
    // Free the memory, not just the elements: `= {}` picks operator=(initializer_list), which
    // keeps the capacity, and every committed chunk would stay resident until the build ends.
    subtree.triangles = std::vector<storage::PackedTriangle>();
    subtree.nodePages = std::vector<std::vector<EncodedSubtree::Slot>>();
    return root;
}

} // namespace ff::builder
