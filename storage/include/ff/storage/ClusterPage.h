#pragma once

// Format v2's geometry pages: clusters (ClusterCodec.h) back to back behind a 16-byte header that
// names the prototype whose position grid they are quantized on. A node's payload is a run of
// whole clusters inside one page, addressed by a representation record's (page, offset, length,
// count). storage/FORMAT.md §6.4 documents every byte; `build --format 2` writes it.
//
// Free functions over bytes: indexing a page checks its header and every cluster's header, so
// that decoding, which the cache's decode stage does for a whole page at once, never reads past
// what the page holds; finding a payload checks that its range is exactly a run of clusters.

#include <ff/storage/ClusterCodec.h>
#include <ff/storage/SceneFormat.h>
#include <ff/storage/Status.h>

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace ff::storage {

inline constexpr std::uint32_t kClusterPageMagic = 0x50434646; // "FFCP"
inline constexpr std::size_t kClusterPageHeaderSize = 16;

/** The most a cluster page of `pageSize` decodes to, as vertices (sizeof(PackedVertex) each)
 *  and one-byte indices together: 3 x the page. Writers keep to it and readers check it, so a
 *  decoder's output per page is bounded (the cache budgets a read in flight at its bound):
 *  well-compressed clusters would otherwise decode to up to ~40 x their bytes. */
constexpr std::uint64_t maxDecodedClusterBytes(std::uint32_t pageSize) noexcept {
    return 3ull * pageSize;
}

/** Bytes `vertices` and `indices` take decoded (the quantity maxDecodedClusterBytes bounds). */
constexpr std::uint64_t
decodedClusterBytes(std::uint64_t vertices, std::uint64_t indices) noexcept {
    return vertices * sizeof(PackedVertex) + indices;
}

/** Writes one page's payload: payloads of whole clusters appended in order, each placed whole.
 *  Deterministic: the same payloads in the same order give the same bytes. */
class ClusterPageWriter {
public:
    /** A page of `pageSize` (payload: pagePayloadBytes(pageSize)). */
    ClusterPageWriter(std::uint32_t pageSize, std::uint32_t prototype);

    /** Whether `count` clusters in `clusters` fit what is left: their bytes, and what they
     *  decode to within maxDecodedClusterBytes (false, too, if they are not whole clusters). */
    [[nodiscard]] bool fits(std::span<const std::byte> clusters, std::uint32_t count) const;
    /** Appends `clusters` (`count` encoded clusters, back to back, checked) and returns the byte
     *  offset it starts at in the page. Errors: InvalidArgument when it does not fit (bytes or
     *  decoded size), when the bytes are not `count` whole clusters, or when the page would
     *  hold more than 65,535. */
    [[nodiscard]] Result<std::uint32_t>
    append(std::span<const std::byte> clusters, std::uint32_t count);

    [[nodiscard]] bool empty() const noexcept { return mClusterCount == 0; }
    [[nodiscard]] std::uint32_t clusterCount() const noexcept { return mClusterCount; }
    /** The payload as it stands (header completed), payloadBytes long, zero after the clusters. */
    [[nodiscard]] std::span<const std::byte> bytes();

private:
    /** What `count` clusters in `clusters` decode to, or an error if they are not that. */
    [[nodiscard]] Result<std::uint64_t>
    decodedBytesOf(std::span<const std::byte> clusters, std::uint32_t count) const;

    std::vector<std::byte> mBytes;
    std::uint64_t mDecodedLimit = 0;
    std::uint64_t mDecoded = 0;
    std::uint32_t mUsed = kClusterPageHeaderSize;
    std::uint32_t mClusterCount = 0;
    std::uint32_t mPrototype = 0;
};

/** One cluster of an indexed page, with where its decoded vertices and indices go when the
 *  whole page is decoded in order. */
struct IndexedCluster {
    std::uint32_t offset = 0; ///< in the page payload
    ClusterInfo info;
    std::uint32_t firstVertex = 0; ///< over the page's clusters
    std::uint32_t firstIndex = 0;
};

/** What a page holds, every header checked: decodeClusterPage() can then not overrun. */
struct ClusterPageIndex {
    std::uint32_t prototype = 0;
    std::uint32_t usedBytes = 0;
    std::vector<IndexedCluster> clusters;
    std::uint32_t vertexCount = 0; ///< over all clusters
    std::uint32_t indexCount = 0;
};

/** Checks the header and walks the clusters of the payload of a page of `pageSize`. Errors:
 *  Corrupt ("cluster page: ..."), on truncation, garbage, clusters past usedBytes, a count that
 *  disagrees, or more than maxDecodedClusterBytes decoded. */
[[nodiscard]] Result<ClusterPageIndex>
indexClusterPage(std::span<const std::byte> payload, std::uint32_t pageSize);

/** A payload found in an indexed page: clusters [first, first + count). */
struct ClusterRun {
    std::uint32_t first = 0;
    std::uint32_t count = 0;
};

/** The clusters a representation's (offset, length, count) names among a page's `clusters`
 *  (an index's, in offset order): it must start at a cluster, end at one, and hold exactly
 *  `count`. Errors: Corrupt. */
[[nodiscard]] Result<ClusterRun> findClusterRun(
        std::span<const IndexedCluster> clusters,
        std::uint32_t offset,
        std::uint32_t length,
        std::uint32_t count);

/** Decodes every cluster of an indexed page (`payload` must be the bytes `index` was made
 *  from) into `vertices` (index.vertexCount) and `indices`
 *  (index.indexCount, cluster-local, as decodeCluster gives them), dequantized on `grid` (the
 *  grid of index.prototype). A corrupt stream is an error; the spans then hold garbage. */
[[nodiscard]] Status decodeClusterPage(
        std::span<const std::byte> payload,
        const ClusterPageIndex& index,
        const PositionGrid& grid,
        std::span<PackedVertex> vertices,
        std::span<std::uint8_t> indices);

/** decodeClusterPage() over a table of clusters kept apart from their page (the runtime's cache
 *  keeps the table beside the encoded bytes): `payload` holds the page's encoded bytes from
 *  offset 0, and each cluster's bytes, vertices and indices are checked to lie inside
 *  `payload`, `vertices` and `indices` (Corrupt otherwise), so a table of any origin is safe. */
[[nodiscard]] Status decodeClusters(
        std::span<const std::byte> payload,
        std::span<const IndexedCluster> clusters,
        const PositionGrid& grid,
        std::span<PackedVertex> vertices,
        std::span<std::uint8_t> indices);

} // namespace ff::storage
