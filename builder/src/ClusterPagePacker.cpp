#include "ClusterPagePacker.h"

#include <ff/storage/Assert.h>

#include <optional>

namespace ff::builder {

ClusterPagePacker::ClusterPagePacker(storage::SceneWriter& writer, std::uint32_t prototype)
    : mWriter(writer)
    , mPrototype(prototype) {}

Status ClusterPagePacker::closeOldest() {
    OpenPage& oldest = mOpen.front();
    // Pages are numbered as they open and written as they close, both oldest first, so the
    // page written now is page mFilePages.size() of this packer.
    FF_ASSERT(oldest.local == mFilePages.size() && !oldest.writer.empty());
    FF_ASSIGN_OR_RETURN(
            const std::uint64_t page,
            mWriter.appendPage(storage::PageType::Geometry, oldest.writer.bytes()));
    if (page > 0xFFFFFFFFull)
        return Status(
                ErrorCode::Unsupported,
                "scene needs more than 2^32 pages; use a larger --page-size");
    mFilePages.push_back(static_cast<std::uint32_t>(page));
    mOpen.pop_front();
    return Status::ok();
}

Status ClusterPagePacker::placeStandIn(
        std::span<const std::byte> clusters,
        std::uint32_t count,
        float error,
        storage::RepresentationKind kind,
        std::vector<storage::RepresentationRecord>& out) {
    const std::size_t first = out.size();
    FF_RETURN_IF_ERROR(place(clusters, count, out));
    for (std::size_t r = first; r < out.size(); ++r) {
        out[r].kind = kind;
        out[r].flags = static_cast<std::uint8_t>(out[r].flags | storage::kRepresentationStandIn);
        out[r].parameter = error;
    }
    return Status::ok();
}

Status ClusterPagePacker::finish() {
    while (!mOpen.empty())
        FF_RETURN_IF_ERROR(closeOldest());
    return Status::ok();
}

Status ClusterPagePacker::fill(
        OpenPage& page,
        std::vector<std::span<const std::byte>>& remaining,
        std::vector<storage::RepresentationRecord>& out) {
    std::optional<storage::RepresentationRecord> run;
    std::size_t kept = 0;
    for (const std::span<const std::byte> cluster : remaining) {
        if (!page.writer.fits(cluster, 1) || (run && run->count == 0xFFFF)) {
            remaining[kept++] = cluster;
            continue;
        }
        FF_ASSIGN_OR_RETURN(const std::uint32_t offset, page.writer.append(cluster, 1));
        if (!run) {
            run = storage::RepresentationRecord{};
            run->kind = storage::RepresentationKind::Clusters;
            run->page = page.local;
            run->offset = offset;
        }
        run->length = offset + static_cast<std::uint32_t>(cluster.size()) - run->offset;
        ++run->count;
    }
    remaining.resize(kept);
    if (run)
        out.push_back(*run);
    return Status::ok();
}

Status ClusterPagePacker::place(
        std::span<const std::byte> clusters,
        std::uint32_t count,
        std::vector<storage::RepresentationRecord>& out) {
    if (count == 0)
        return Status::ok();
    // Each cluster decodes alone, so a node's clusters may go in any order: each open page,
    // oldest first, takes those that fit, as one run (a node gets one representation per page
    // it reaches). Then new pages take the rest. (Measured: 27 % of the encoded bytes were
    // slack at 4 KiB pages and 13 % at 64 KiB when payloads were kept whole.)
    std::vector<std::span<const std::byte>> remaining;
    remaining.reserve(count);
    while (!clusters.empty()) {
        FF_ASSIGN_OR_RETURN(const storage::ClusterInfo info, storage::readClusterInfo(clusters));
        remaining.push_back(clusters.first(info.encodedBytes));
        clusters = clusters.subspan(info.encodedBytes);
    }
    if (remaining.size() != count)
        return Status(ErrorCode::Internal, "the cluster count disagrees with the clusters");
    for (OpenPage& page : mOpen) {
        if (remaining.empty())
            return Status::ok();
        FF_RETURN_IF_ERROR(fill(page, remaining, out));
    }
    while (!remaining.empty()) {
        if (mOpen.size() == kOpenPages)
            FF_RETURN_IF_ERROR(closeOldest());
        mOpen.push_back({storage::ClusterPageWriter(mWriter.pageSize(), mPrototype), mOpened++});
        const std::size_t before = remaining.size();
        FF_RETURN_IF_ERROR(fill(mOpen.back(), remaining, out));
        if (remaining.size() == before) {
            mOpen.pop_back();
            return Status(ErrorCode::Internal, "a cluster larger than a page");
        }
    }
    return Status::ok();
}

} // namespace ff::builder
