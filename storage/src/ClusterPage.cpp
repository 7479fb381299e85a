#include <ff/storage/Assert.h>
#include <ff/storage/ClusterPage.h>

#include <cstring>
#include <limits>
#include <string>

namespace ff::storage {

namespace {

struct ClusterPageHeader {
    std::uint32_t magic;
    std::uint32_t prototype;
    std::uint16_t clusterCount;
    std::uint16_t reserved;  ///< 0
    std::uint32_t usedBytes; ///< header and clusters
};
static_assert(sizeof(ClusterPageHeader) == kClusterPageHeaderSize);

constexpr std::uint32_t kMaxPageClusters = std::numeric_limits<std::uint16_t>::max();

Status corrupt(const std::string& what) {
    return {ErrorCode::Corrupt, "cluster page: " + what};
}

} // namespace

ClusterPageWriter::ClusterPageWriter(std::uint32_t pageSize, std::uint32_t prototype)
    : mBytes(pagePayloadBytes(pageSize))
    , mDecodedLimit(maxDecodedClusterBytes(pageSize))
    , mPrototype(prototype) {
    FF_ASSERT(isValidPageSize(pageSize));
}

Result<std::uint64_t>
ClusterPageWriter::decodedBytesOf(std::span<const std::byte> clusters, std::uint32_t count) const {
    if (count == 0 || count > kMaxPageClusters - mClusterCount)
        return Status(ErrorCode::InvalidArgument, "a page holds 1 to 65,535 clusters");
    // The payload must be exactly `count` whole clusters: what a reader will find there.
    std::size_t at = 0;
    std::uint64_t decoded = 0;
    for (std::uint32_t c = 0; c < count; ++c) {
        FF_ASSIGN_OR_RETURN(const ClusterInfo info, readClusterInfo(clusters.subspan(at)));
        at += info.encodedBytes;
        decoded += decodedClusterBytes(info.vertexCount, std::uint64_t{info.triangleCount} * 3);
    }
    if (at != clusters.size())
        return Status(
                ErrorCode::InvalidArgument,
                std::to_string(count) + " clusters take " + std::to_string(at) +
                        " of the payload's " + std::to_string(clusters.size()) + " bytes");
    return decoded;
}

bool ClusterPageWriter::fits(std::span<const std::byte> clusters, std::uint32_t count) const {
    const Result<std::uint64_t> decoded = decodedBytesOf(clusters, count);
    return decoded.isOk() && clusters.size() <= mBytes.size() - mUsed &&
           mDecoded + *decoded <= mDecodedLimit;
}

Result<std::uint32_t>
ClusterPageWriter::append(std::span<const std::byte> clusters, std::uint32_t count) {
    FF_ASSIGN_OR_RETURN(const std::uint64_t decoded, decodedBytesOf(clusters, count));
    if (clusters.size() > mBytes.size() - mUsed)
        return Status(
                ErrorCode::InvalidArgument,
                "a payload of " + std::to_string(clusters.size()) + " bytes does not fit the " +
                        std::to_string(mBytes.size() - mUsed) + " left in the page");
    if (mDecoded + decoded > mDecodedLimit)
        return Status(
                ErrorCode::InvalidArgument,
                "a payload decoding to " + std::to_string(decoded) +
                        " bytes would take the page past " + std::to_string(mDecodedLimit) +
                        " decoded");
    mDecoded += decoded;
    const std::uint32_t offset = mUsed;
    std::memcpy(mBytes.data() + offset, clusters.data(), clusters.size());
    mUsed += static_cast<std::uint32_t>(clusters.size());
    mClusterCount += count;
    return offset;
}

std::span<const std::byte> ClusterPageWriter::bytes() {
    const ClusterPageHeader header{
            kClusterPageMagic, mPrototype, static_cast<std::uint16_t>(mClusterCount), 0, mUsed};
    std::memcpy(mBytes.data(), &header, sizeof(header));
    return mBytes;
}

Result<ClusterPageIndex>
indexClusterPage(std::span<const std::byte> payload, std::uint32_t pageSize) {
    if (payload.size() < sizeof(ClusterPageHeader))
        return corrupt("truncated header (" + std::to_string(payload.size()) + " bytes)");
    ClusterPageHeader header{};
    std::memcpy(&header, payload.data(), sizeof(header));
    if (header.magic != kClusterPageMagic)
        return corrupt("bad magic");
    if (header.reserved != 0)
        return corrupt("reserved field " + std::to_string(header.reserved));
    if (header.usedBytes < sizeof(ClusterPageHeader) || header.usedBytes > payload.size())
        return corrupt(
                "used bytes " + std::to_string(header.usedBytes) + " outside [16, " +
                std::to_string(payload.size()) + "]");
    if (header.clusterCount == 0)
        return corrupt("no clusters");
    ClusterPageIndex index;
    index.prototype = header.prototype;
    index.usedBytes = header.usedBytes;
    index.clusters.reserve(header.clusterCount);
    const std::span<const std::byte> used = payload.first(header.usedBytes);
    std::uint32_t at = sizeof(ClusterPageHeader);
    for (std::uint32_t c = 0; c < header.clusterCount; ++c) {
        auto info = readClusterInfo(used.subspan(at));
        if (!info)
            return corrupt(
                    "at byte " + std::to_string(at) + " (cluster " + std::to_string(c) +
                    "): " + info.status().message());
        index.clusters.push_back({at, *info, index.vertexCount, index.indexCount});
        index.vertexCount += info->vertexCount;
        index.indexCount += info->triangleCount * 3;
        at += info->encodedBytes;
    }
    const std::uint64_t decoded = decodedClusterBytes(index.vertexCount, index.indexCount);
    if (decoded > maxDecodedClusterBytes(pageSize))
        return corrupt(
                "decodes to " + std::to_string(decoded) + " bytes, more than the " +
                std::to_string(maxDecodedClusterBytes(pageSize)) + " a page may");
    if (at != header.usedBytes)
        return corrupt(
                std::to_string(header.clusterCount) + " clusters end at byte " +
                std::to_string(at) + ", the header says " + std::to_string(header.usedBytes));
    return index;
}

Result<ClusterRun> findClusterRun(
        std::span<const IndexedCluster> clusters,
        std::uint32_t offset,
        std::uint32_t length,
        std::uint32_t count) {
    // Clusters are in offset order: the first at or after `offset`.
    std::size_t lo = 0;
    std::size_t hi = clusters.size();
    while (lo < hi) {
        const std::size_t mid = (lo + hi) / 2;
        if (clusters[mid].offset < offset)
            lo = mid + 1;
        else
            hi = mid;
    }
    const auto where = [&] {
        return "payload at byte " + std::to_string(offset) + " (" + std::to_string(length) +
               " bytes, " + std::to_string(count) + " clusters)";
    };
    if (lo == clusters.size() || clusters[lo].offset != offset)
        return corrupt(where() + " does not start at a cluster");
    if (count == 0 || count > clusters.size() - lo)
        return corrupt(
                where() + " runs past the page's " + std::to_string(clusters.size()) + " clusters");
    const IndexedCluster& last = clusters[lo + count - 1];
    if (std::uint64_t{offset} + length != std::uint64_t{last.offset} + last.info.encodedBytes)
        return corrupt(where() + " does not end where its last cluster does");
    return ClusterRun{static_cast<std::uint32_t>(lo), count};
}

Status decodeClusterPage(
        std::span<const std::byte> payload,
        const ClusterPageIndex& index,
        const PositionGrid& grid,
        std::span<PackedVertex> vertices,
        std::span<std::uint8_t> indices) {
    FF_ASSERT(vertices.size() >= index.vertexCount && indices.size() >= index.indexCount);
    FF_ASSERT(payload.size() >= index.usedBytes);
    return decodeClusters(payload.first(index.usedBytes), index.clusters, grid, vertices, indices);
}

Status decodeClusters(
        std::span<const std::byte> payload,
        std::span<const IndexedCluster> clusters,
        const PositionGrid& grid,
        std::span<PackedVertex> vertices,
        std::span<std::uint8_t> indices) {
    for (const IndexedCluster& c : clusters) {
        if (std::uint64_t{c.offset} + c.info.encodedBytes > payload.size() ||
            std::uint64_t{c.firstVertex} + c.info.vertexCount > vertices.size() ||
            std::uint64_t{c.firstIndex} + std::uint64_t{c.info.triangleCount} * 3 > indices.size())
            return corrupt("cluster at byte " + std::to_string(c.offset) + " runs past its page");
        const Status decoded = decodeCluster(
                payload.subspan(c.offset, c.info.encodedBytes),
                grid,
                vertices.subspan(c.firstVertex, c.info.vertexCount),
                indices.subspan(c.firstIndex, std::size_t{c.info.triangleCount} * 3));
        if (!decoded.isOk())
            return corrupt("at byte " + std::to_string(c.offset) + ": " + decoded.message());
    }
    return Status::ok();
}

} // namespace ff::storage
