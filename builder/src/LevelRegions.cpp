#include "LevelRegions.h"

#include <ff/storage/Assert.h>

#include <algorithm>
#include <cstring>
#include <span>

namespace ff::builder {

namespace {

// Small appends (a chunk's shallow levels) are gathered; a chunk's deep levels write through.
constexpr std::size_t kSpillBufferBytes = 64u << 10;

} // namespace

LevelRegions::Region::Region(const std::filesystem::path& recordPath, SpillCodec codec) : records(recordPath, codec) {
    records.setBufferLimit(kSpillBufferBytes);
}

LevelRegions::LevelRegions(
        storage::SceneWriter& writer,
        std::filesystem::path directory,
        SpillCodec codec,
        std::string prefix,
        std::uint64_t extentBytes)
    : mWriter(writer)
    , mDirectory(std::move(directory))
    , mCodec(codec)
    , mPrefix(std::move(prefix))
    , mPageSize(writer.pageSize())
    , mExtentTriangles(std::max<std::uint64_t>(extentBytes / mPageSize, 1) * storage::trianglesPerPage(mPageSize)) {}

LevelRegions::Region& LevelRegions::region(std::uint32_t level) {
    while (mRegions.size() <= level) {
        const std::string name = mPrefix + "-level" + std::to_string(mRegions.size()) + ".nodes";
        mRegions.push_back(std::make_unique<Region>(mDirectory / name, mCodec));
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

Result<TriangleSlot> LevelRegions::placeRun(Region& r, std::span<const storage::PackedTriangle> run) {
    if (!r.extent.empty() && r.extent.size() + run.size() > mExtentTriangles)
        FF_RETURN_IF_ERROR(writeExtent(r));
    const std::uint64_t perPage = storage::trianglesPerPage(mPageSize);
    const std::uint64_t at = r.extent.size();
    r.extent.insert(r.extent.end(), run.begin(), run.end());
    return TriangleSlot{
            r.extentFirstPage + static_cast<std::uint32_t>(at / perPage), static_cast<std::uint32_t>(at % perPage)};
}

Status LevelRegions::writeExtent(Region& r) {
    const std::uint64_t perPage = storage::trianglesPerPage(mPageSize);
    for (std::uint64_t first = 0; first < r.extent.size(); first += perPage) {
        const std::uint64_t count = std::min<std::uint64_t>(perPage, r.extent.size() - first);
        const auto payload = std::as_bytes(std::span(r.extent).subspan(first, count));
        FF_ASSIGN_OR_RETURN(const std::uint64_t page, mWriter.appendPage(storage::PageType::Geometry, payload));
        if (page > 0xFFFFFFFFull)
            return Status(ErrorCode::Unsupported, "scene needs more than 2^32 pages; use a larger --page-size");
        r.geometryPage.push_back(static_cast<std::uint32_t>(page));
    }
    r.extentFirstPage = static_cast<std::uint32_t>(r.geometryPage.size());
    if (r.extent.capacity() > mExtentTriangles) // a run longer than an extent: do not keep its memory
        r.extent = std::vector<storage::PackedTriangle>();
    r.extent.clear();
    return Status::ok();
}

Status LevelRegions::append(LevelledSubtree& chunk) {
    const std::size_t depths = chunk.levels.size();
    // Where each record lands. Each level is placed on its own, block after block.
    std::vector<std::vector<storage::NodeRef>> where(depths);
    for (std::size_t d = 0; d < depths; ++d) {
        Region& r = region(chunk.rootLevel + static_cast<std::uint32_t>(d));
        const LevelledSubtree::Level& level = chunk.levels[d];
        where[d].reserve(level.records.size());
        for (const std::uint8_t count : level.blocks) {
            const storage::NodeRef first = placeBlock(r, count);
            for (std::uint32_t k = 0; k < count; ++k)
                where[d].push_back({first.page, first.slot + k});
        }
        FF_ASSERT(where[d].size() == level.records.size());
    }
    BuildNode& root = chunk.root;
    for (std::size_t d = 0; d < depths; ++d) {
        Region& r = region(chunk.rootLevel + static_cast<std::uint32_t>(d));
        LevelledSubtree::Level& level = chunk.levels[d];
        const auto triangles = std::span(chunk.triangles).subspan(level.triangleBegin, level.triangleCount);
        if (d == 0 && root.placedTriangles) {
            const auto run = triangles.subspan(root.placedTriangles->slot, root.triangleCount);
            FF_ASSIGN_OR_RETURN(root.placedTriangles, placeRun(r, run));
        }
        for (storage::NodeRecord& record : level.records) {
            FF_ASSERT(record.kind == static_cast<std::uint8_t>(storage::NodeKind::Cell));
            if (record.childCount > 0)
                record.firstChild = where.at(d + 1).at(record.firstChild.slot);
            if (record.geometryCount > 0) {
                const auto run = triangles.subspan(record.geometryFirst, record.geometryCount);
                FF_ASSIGN_OR_RETURN(const TriangleSlot start, placeRun(r, run));
                record.geometryPage = start.page;
                record.geometryFirst = start.slot;
            }
        }
        FF_RETURN_IF_ERROR(r.records.append(level.records));
    }
    if (root.placedChildren)
        root.placedChildren = where.at(1).at(root.placedChildren->slot);
    // Free the memory, not just the elements (see commitSubtree).
    chunk.levels = std::vector<LevelledSubtree::Level>();
    chunk.triangles = std::vector<storage::PackedTriangle>();
    return Status::ok();
}

Status LevelRegions::finish(const std::function<void(std::uint64_t done, std::uint64_t total)>& pagesCopied) {
    FF_ASSERT(mWriter.pageSize() == mPageSize);
    for (const auto& r : mRegions) {
        FF_RETURN_IF_ERROR(writeExtent(*r));
        r->extent = std::vector<storage::PackedTriangle>();
    }
    const std::uint64_t totalPages = nodePages();
    std::uint64_t copied = 0;
    const auto pageWritten = [&] {
        if (pagesCopied)
            pagesCopied(++copied, totalPages);
    };
    std::uint64_t next = mWriter.nextPageIndex();
    for (const auto& r : mRegions) {
        r->firstNodePage = next;
        next += r->pageFill.size();
    }
    if (next > 0xFFFFFFFFull)
        return Status(ErrorCode::Unsupported, "scene needs more than 2^32 pages; use a larger --page-size");
    for (std::size_t level = 0; level < mRegions.size(); ++level) {
        const Region* below = level + 1 < mRegions.size() ? mRegions[level + 1].get() : nullptr;
        FF_RETURN_IF_ERROR(copyNodePages(*mRegions[level], below, pageWritten));
    }
    return Status::ok();
}

Status LevelRegions::copyNodePages(Region& r, const Region* below, const std::function<void()>& pageWritten) {
    if (r.pageFill.empty())
        return Status::ok();
    FF_ASSERT(mWriter.nextPageIndex() == r.firstNodePage);
    std::vector<storage::NodeRecord> pending; // records read but not yet written, < 2 pages
    std::vector<std::byte> payload;
    std::size_t page = 0;
    const std::size_t batchSize = storage::nodesPerPage(mPageSize);
    FF_RETURN_IF_ERROR(r.records.forEachBatch(batchSize, [&](std::span<const storage::NodeRecord> batch) -> Status {
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
                    record.geometryPage = r.geometryPage.at(record.geometryPage);
                std::memcpy(payload.data() + i * sizeof(record), &record, sizeof(record));
            }
            FF_RETURN_IF_ERROR(mWriter.appendPage(storage::PageType::Nodes, payload).status());
            pageWritten();
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
    return {mRegions.at(level)->geometryPage.at(start.page), start.slot};
}

std::uint64_t LevelRegions::nodePages() const noexcept {
    std::uint64_t pages = 0;
    for (const auto& r : mRegions)
        pages += r->pageFill.size();
    return pages;
}

std::uint64_t LevelRegions::geometryPages() const noexcept {
    std::uint64_t pages = 0;
    for (const auto& r : mRegions)
        pages += r->geometryPage.size();
    return pages;
}

std::uint64_t LevelRegions::spillBytes() const noexcept {
    std::uint64_t bytes = 0;
    for (const auto& r : mRegions)
        bytes += r->records.bytesWritten();
    return bytes;
}

} // namespace ff::builder
