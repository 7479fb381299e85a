#include "ClusterPageDecoder.h"

#include <cstring>
#include <memory>
#include <string>

namespace ff::runtime {

namespace {

constexpr std::uint32_t kDecodedMagic = 0x50444646; // "FFDP"

struct DecodedPageHeader {
    std::uint32_t magic;
    std::uint32_t prototype;
    std::uint32_t clusterCount;
    std::uint32_t vertexCount;
    std::uint32_t indexCount;
    std::uint32_t reserved[3];
};
static_assert(sizeof(DecodedPageHeader) == 32);

constexpr std::size_t roundUp4(std::size_t n) {
    return (n + 3) / 4 * 4;
}

/** Where each part of a decoded page starts. */
struct DecodedLayout {
    std::size_t clusters = sizeof(DecodedPageHeader);
    std::size_t vertices = 0;
    std::size_t indices = 0;
    std::size_t trailer = 0;
    std::size_t total = 0;

    DecodedLayout(std::size_t clusterCount, std::size_t vertexCount, std::size_t indexCount) {
        vertices = clusters + clusterCount * sizeof(storage::IndexedCluster);
        indices = vertices + vertexCount * sizeof(storage::PackedVertex);
        trailer = indices + roundUp4(indexCount);
        total = trailer + sizeof(storage::PageTrailer);
    }
};
static_assert(sizeof(storage::IndexedCluster) % 4 == 0 && sizeof(storage::PackedVertex) % 4 == 0);

Status corrupt(std::uint64_t page, const std::string& what) {
    return {ErrorCode::Corrupt, "page " + std::to_string(page) + ": " + what};
}

} // namespace

ClusterPageDecoder::ClusterPageDecoder(std::vector<storage::PositionGrid> grids)
    : mGrids(std::move(grids)) {}

std::size_t ClusterPageDecoder::maxDecodedBytes(std::uint32_t pageSize) const {
    // Vertices and indices within maxDecodedClusterBytes; a cluster takes at least its 20-byte
    // header and two non-empty streams of the page, so at most payload / 22 of them.
    const std::size_t clusters = storage::pagePayloadBytes(pageSize) / 22;
    return sizeof(DecodedPageHeader) + clusters * sizeof(storage::IndexedCluster) +
           storage::maxDecodedClusterBytes(pageSize) + 3 + sizeof(storage::PageTrailer);
}

Status ClusterPageDecoder::decode(std::uint64_t index, cache::PageBuffer& page) {
    const std::span<const std::byte> raw = page.view();
    storage::PageTrailer trailer{};
    std::memcpy(&trailer, raw.data() + raw.size() - sizeof(trailer), sizeof(trailer));
    if (trailer.pageType != static_cast<std::uint16_t>(storage::PageType::Geometry))
        return Status::ok(); // nodes and tables are read as they are
    const auto pageSize = static_cast<std::uint32_t>(raw.size());
    const std::span<const std::byte> payload = raw.first(storage::pagePayloadBytes(pageSize));
    auto indexed = storage::indexClusterPage(payload, pageSize);
    if (!indexed)
        return indexed.status().withContext("page " + std::to_string(index));
    const storage::ClusterPageIndex& clusters = *indexed;
    if (clusters.prototype >= mGrids.size())
        return corrupt(
                index,
                "cluster page of prototype " + std::to_string(clusters.prototype) +
                        ", the file has " + std::to_string(mGrids.size()));

    const DecodedLayout layout(clusters.clusters.size(), clusters.vertexCount, clusters.indexCount);
    cache::PageBuffer decoded{std::make_unique<std::byte[]>(layout.total), layout.total};
    std::byte* out = decoded.bytes.get();
    const DecodedPageHeader header{
            kDecodedMagic,
            clusters.prototype,
            static_cast<std::uint32_t>(clusters.clusters.size()),
            clusters.vertexCount,
            clusters.indexCount,
            {0, 0, 0}};
    std::memcpy(out, &header, sizeof(header));
    std::memcpy(
            out + layout.clusters,
            clusters.clusters.data(),
            clusters.clusters.size() * sizeof(storage::IndexedCluster));
    // Decoded in place: PackedVertex and u8 are implicit-lifetime types, the buffer is new.
    const std::span<storage::PackedVertex> vertices(
            reinterpret_cast<storage::PackedVertex*>(out + layout.vertices), clusters.vertexCount);
    const std::span<std::uint8_t> indices(
            reinterpret_cast<std::uint8_t*>(out + layout.indices), clusters.indexCount);
    const Status status = storage::decodeClusterPage(
            payload, clusters, mGrids[clusters.prototype], vertices, indices);
    if (!status.isOk())
        return status.withContext("page " + std::to_string(index));
    std::memcpy(out + layout.trailer, &trailer, sizeof(trailer));
    page = std::move(decoded);
    return Status::ok();
}

Result<DecodedClusterPage> DecodedClusterPage::view(std::span<const std::byte> payload) {
    DecodedPageHeader header{};
    if (payload.size() < sizeof(header))
        return Status(ErrorCode::Corrupt, "not a decoded cluster page (too short)");
    std::memcpy(&header, payload.data(), sizeof(header));
    if (header.magic != kDecodedMagic)
        return Status(ErrorCode::Corrupt, "not a decoded cluster page (bad magic)");
    const DecodedLayout layout(header.clusterCount, header.vertexCount, header.indexCount);
    if (layout.trailer != payload.size())
        return Status(ErrorCode::Corrupt, "a decoded cluster page of the wrong size");
    DecodedClusterPage page;
    page.mPrototype = header.prototype;
    page.mClusters = {
            reinterpret_cast<const storage::IndexedCluster*>(payload.data() + layout.clusters),
            header.clusterCount};
    page.mVertices = {
            reinterpret_cast<const storage::PackedVertex*>(payload.data() + layout.vertices),
            header.vertexCount};
    page.mIndices = {
            reinterpret_cast<const std::uint8_t*>(payload.data() + layout.indices),
            header.indexCount};
    return page;
}

} // namespace ff::runtime
