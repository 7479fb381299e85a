#include "CachedClusterPage.h"

#include <cstring>
#include <memory>
#include <string>

namespace ff::runtime {

namespace {

constexpr std::uint32_t kCachedMagic = 0x50494646; // "FFIP": an indexed page

struct CachedPageHeader {
    std::uint32_t magic;
    std::uint32_t prototype;
    std::uint32_t clusterCount;
    std::uint32_t vertexCount;
    std::uint32_t indexCount;
    std::uint32_t encodedBytes;
    std::uint32_t reserved[2];
};
static_assert(sizeof(CachedPageHeader) == 32);

constexpr std::size_t roundUp4(std::size_t n) {
    return (n + 3) / 4 * 4;
}

/** Where each part of a cached page starts. */
struct CachedLayout {
    std::size_t clusters = sizeof(CachedPageHeader);
    std::size_t encoded = 0;
    std::size_t trailer = 0;
    std::size_t total = 0;

    CachedLayout(std::size_t clusterCount, std::size_t encodedBytes) {
        encoded = clusters + clusterCount * sizeof(storage::IndexedCluster);
        trailer = encoded + roundUp4(encodedBytes);
        total = trailer + sizeof(storage::PageTrailer);
    }
};
static_assert(sizeof(storage::IndexedCluster) % 4 == 0);

Status corrupt(std::uint64_t page, const std::string& what) {
    return {ErrorCode::Corrupt, "page " + std::to_string(page) + ": " + what};
}

} // namespace

ClusterPageIndexer::ClusterPageIndexer(std::vector<storage::PositionGrid> grids)
    : mGrids(std::move(grids)) {}

std::size_t ClusterPageIndexer::maxDecodedBytes(std::uint32_t pageSize) const {
    // A cluster takes at least its 20-byte header and two non-empty streams of the page, so
    // there are at most payload / 22 of them; the encoded bytes are at most the payload.
    const std::size_t payload = storage::pagePayloadBytes(pageSize);
    return CachedLayout(payload / 22, payload).total;
}

Status ClusterPageIndexer::decode(std::uint64_t index, cache::PageBuffer& page) {
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

    const CachedLayout layout(clusters.clusters.size(), clusters.usedBytes);
    cache::PageBuffer cached{std::make_unique<std::byte[]>(layout.total), layout.total};
    std::byte* out = cached.bytes.get();
    std::memset(out, 0, layout.total);
    const CachedPageHeader header{
            kCachedMagic,
            clusters.prototype,
            static_cast<std::uint32_t>(clusters.clusters.size()),
            clusters.vertexCount,
            clusters.indexCount,
            clusters.usedBytes,
            {0, 0}};
    std::memcpy(out, &header, sizeof(header));
    std::memcpy(
            out + layout.clusters,
            clusters.clusters.data(),
            clusters.clusters.size() * sizeof(storage::IndexedCluster));
    std::memcpy(out + layout.encoded, payload.data(), clusters.usedBytes);
    std::memcpy(out + layout.trailer, &trailer, sizeof(trailer));
    page = std::move(cached);
    return Status::ok();
}

Result<CachedClusterPage> CachedClusterPage::view(std::span<const std::byte> payload) {
    CachedPageHeader header{};
    if (payload.size() < sizeof(header))
        return Status(ErrorCode::Corrupt, "not a cached cluster page (too short)");
    std::memcpy(&header, payload.data(), sizeof(header));
    if (header.magic != kCachedMagic)
        return Status(ErrorCode::Corrupt, "not a cached cluster page (bad magic)");
    const CachedLayout layout(header.clusterCount, header.encodedBytes);
    if (layout.trailer != payload.size())
        return Status(ErrorCode::Corrupt, "a cached cluster page of the wrong size");
    CachedClusterPage page;
    page.mPrototype = header.prototype;
    page.mVertexCount = header.vertexCount;
    page.mIndexCount = header.indexCount;
    page.mClusters = {
            reinterpret_cast<const storage::IndexedCluster*>(payload.data() + layout.clusters),
            header.clusterCount};
    page.mEncoded = payload.subspan(layout.encoded, header.encodedBytes);
    return page;
}

Result<DecodedGeometry> decodeCachedPage(
        const CachedClusterPage& page,
        std::span<const storage::PositionGrid> grids,
        std::uint64_t maxBytes) {
    if (storage::decodedClusterBytes(page.vertexCount(), page.indexCount()) > maxBytes)
        return Status(ErrorCode::Corrupt, "cluster page decodes to more than a page may");
    if (page.prototype() >= grids.size())
        return Status(
                ErrorCode::Corrupt,
                "cluster page of prototype " + std::to_string(page.prototype()) +
                        ", the file has " + std::to_string(grids.size()));
    DecodedGeometry decoded;
    decoded.vertexCount = page.vertexCount();
    decoded.indexCount = page.indexCount();
    decoded.bytes = std::make_unique<std::byte[]>(decoded.size());
    // Decoded in place: PackedVertex and u8 are implicit-lifetime types, the buffer is new.
    const std::span<storage::PackedVertex> vertices(
            reinterpret_cast<storage::PackedVertex*>(decoded.bytes.get()), decoded.vertexCount);
    const std::span<std::uint8_t> indices(
            reinterpret_cast<std::uint8_t*>(decoded.bytes.get()) + vertices.size_bytes(),
            decoded.indexCount);
    FF_RETURN_IF_ERROR(storage::decodeClusters(
            page.encoded(), page.clusters(), grids[page.prototype()], vertices, indices));
    return decoded;
}

} // namespace ff::runtime
