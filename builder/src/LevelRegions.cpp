#include "LevelRegions.h"

#include <ff/storage/Assert.h>

#include <cstring>
#include <span>

namespace ff::builder {

namespace {

// Small appends (a chunk's shallow levels) are gathered; a chunk's deep levels write through.
constexpr std::size_t kSpillBufferBytes = 64u << 10;

} // namespace

LevelRegions::Region::Region(const std::filesystem::path& recordPath, const std::filesystem::path& trianglePath)
    : records(recordPath), triangles(trianglePath) {
    records.setBufferLimit(kSpillBufferBytes);
    triangles.setBufferLimit(kSpillBufferBytes);
}

LevelRegions::LevelRegions(std::filesystem::path directory, std::string prefix, std::uint32_t pageSize)
    : mDirectory(std::move(directory)), mPrefix(std::move(prefix)), mPageSize(pageSize) {}

LevelRegions::Region& LevelRegions::region(std::uint32_t level) {
    while (mRegions.size() <= level) {
        const std::string name = mPrefix + "-level" + std::to_string(mRegions.size());
        mRegions.push_back(std::make_unique<Region>(mDirectory / (name + ".nodes"), mDirectory / (name + ".run")));
    }
    return *mRegions[level];
}

storage::NodeRef LevelRegions::placeBlock(Region& r, std::uint32_t count) {
    const std::uint32_t perPage = storage::nodesPerPage(mPageSize);
    FF_ASSERT(count > 0 && count <= perPage);
    if (r.pageFill.empty() || r.pageFill.back() + count > perPage)
        r.pageFill.push_back(0);
    const storage::NodeRef first{static_cast<std::uint32_t>(r.pageFill.size() - 1), r.pageFill.back()};
    r.pageFill.back() += count;
    return first;
}

TriangleSlot LevelRegions::triangleSlot(std::uint64_t index) const {
    const std::uint64_t perPage = storage::trianglesPerPage(mPageSize);
    return {static_cast<std::uint32_t>(index / perPage), static_cast<std::uint32_t>(index % perPage)};
}

Status LevelRegions::append(LevelledSubtree& chunk) {
    const std::size_t depths = chunk.levels.size();
    // Where each record lands. Each level is placed on its own, block after block.
    std::vector<std::vector<storage::NodeRef>> where(depths);
    std::vector<std::uint64_t> triangleBase(depths);
    for (std::size_t d = 0; d < depths; ++d) {
        Region& r = region(chunk.rootLevel + static_cast<std::uint32_t>(d));
        const LevelledSubtree::Level& level = chunk.levels[d];
        triangleBase[d] = r.triangleCount;
        where[d].reserve(level.records.size());
        for (const std::uint8_t count : level.blocks) {
            const storage::NodeRef first = placeBlock(r, count);
            for (std::uint32_t k = 0; k < count; ++k)
                where[d].push_back({first.page, first.slot + k});
        }
        FF_ASSERT(where[d].size() == level.records.size());
    }
    for (std::size_t d = 0; d < depths; ++d) {
        Region& r = region(chunk.rootLevel + static_cast<std::uint32_t>(d));
        LevelledSubtree::Level& level = chunk.levels[d];
        for (storage::NodeRecord& record : level.records) {
            FF_ASSERT(record.kind == static_cast<std::uint8_t>(storage::NodeKind::Cell));
            if (record.childCount > 0)
                record.firstChild = where.at(d + 1).at(record.firstChild.slot);
            if (record.geometryCount > 0) {
                const TriangleSlot start = triangleSlot(triangleBase[d] + record.geometryFirst);
                record.geometryPage = start.page;
                record.geometryFirst = start.slot;
            }
        }
        FF_RETURN_IF_ERROR(r.records.append(level.records));
        FF_RETURN_IF_ERROR(r.triangles.append(std::span(chunk.triangles).subspan(level.triangleBegin, level.triangleCount)));
        r.triangleCount += level.triangleCount;
    }
    for (BuildNode& node : chunk.crown) {
        const std::size_t d = node.level - chunk.rootLevel;
        if (node.placedChildren)
            node.placedChildren = where.at(d + 1).at(node.placedChildren->slot);
        if (node.placedTriangles)
            node.placedTriangles = triangleSlot(triangleBase[d] + node.placedTriangles->slot);
    }
    // Free the memory, not just the elements (see commitSubtree).
    chunk.levels = std::vector<LevelledSubtree::Level>();
    chunk.triangles = std::vector<storage::PackedTriangle>();
    return Status::ok();
}

Status LevelRegions::writeTo(storage::SceneWriter& writer) {
    FF_ASSERT(writer.pageSize() == mPageSize);
    const std::uint32_t trianglesPerPage = storage::trianglesPerPage(mPageSize);
    for (const auto& r : mRegions) {
        r->firstGeometryPage = writer.nextPageIndex();
        if (r->triangleCount > 0) {
            FF_RETURN_IF_ERROR(r->triangles.forEachBatch(trianglesPerPage, [&](std::span<const storage::PackedTriangle> page) {
                return writer.appendPage(storage::PageType::Geometry, std::as_bytes(page)).status();
            }));
        }
        r->triangles.remove(); // disk space comes back level by level
    }
    std::uint64_t next = writer.nextPageIndex();
    for (const auto& r : mRegions) {
        r->firstNodePage = next;
        next += r->pageFill.size();
    }
    for (std::size_t level = 0; level < mRegions.size(); ++level) {
        const Region* below = level + 1 < mRegions.size() ? mRegions[level + 1].get() : nullptr;
        FF_RETURN_IF_ERROR(copyNodePages(*mRegions[level], below, writer));
    }
    return Status::ok();
}

Status LevelRegions::copyNodePages(Region& r, const Region* below, storage::SceneWriter& writer) {
    if (r.pageFill.empty())
        return Status::ok();
    FF_ASSERT(writer.nextPageIndex() == r.firstNodePage);
    std::vector<storage::NodeRecord> pending; // records read but not yet written, < 2 pages
    std::vector<std::byte> payload;
    std::size_t page = 0;
    FF_RETURN_IF_ERROR(r.records.forEachBatch(storage::nodesPerPage(mPageSize), [&](std::span<const storage::NodeRecord> batch) -> Status {
        pending.insert(pending.end(), batch.begin(), batch.end());
        std::size_t used = 0;
        while (page < r.pageFill.size() && pending.size() - used >= r.pageFill[page]) {
            const std::uint32_t count = r.pageFill[page];
            payload.resize(count * sizeof(storage::NodeRecord));
            for (std::uint32_t i = 0; i < count; ++i) {
                storage::NodeRecord record = pending[used + i];
                if (record.childCount > 0) {
                    FF_ASSERT(below != nullptr);
                    record.firstChild.page += static_cast<std::uint32_t>(below->firstNodePage);
                }
                if (record.geometryCount > 0)
                    record.geometryPage += static_cast<std::uint32_t>(r.firstGeometryPage);
                std::memcpy(payload.data() + i * sizeof(record), &record, sizeof(record));
            }
            FF_RETURN_IF_ERROR(writer.appendPage(storage::PageType::Nodes, payload).status());
            used += count;
            ++page;
        }
        pending.erase(pending.begin(), pending.begin() + static_cast<std::ptrdiff_t>(used));
        return Status::ok();
    }));
    FF_ASSERT(page == r.pageFill.size() && pending.empty());
    r.records.remove();
    return Status::ok();
}

storage::NodeRef LevelRegions::absoluteChildren(std::uint32_t level, storage::NodeRef ref) const {
    return {ref.page + static_cast<std::uint32_t>(mRegions.at(level)->firstNodePage), ref.slot};
}

TriangleSlot LevelRegions::absoluteTriangles(std::uint32_t level, TriangleSlot start) const {
    return {start.page + static_cast<std::uint32_t>(mRegions.at(level)->firstGeometryPage), start.slot};
}

std::uint64_t LevelRegions::nodePages() const noexcept {
    std::uint64_t pages = 0;
    for (const auto& r : mRegions)
        pages += r->pageFill.size();
    return pages;
}

std::uint64_t LevelRegions::geometryPages() const noexcept {
    const std::uint64_t perPage = storage::trianglesPerPage(mPageSize);
    std::uint64_t pages = 0;
    for (const auto& r : mRegions)
        pages += (r->triangleCount + perPage - 1) / perPage;
    return pages;
}

std::uint64_t LevelRegions::spillBytes() const noexcept {
    std::uint64_t bytes = 0;
    for (const auto& r : mRegions)
        bytes += r->records.bytesWritten() + r->triangles.bytesWritten();
    return bytes;
}

} // namespace ff::builder
