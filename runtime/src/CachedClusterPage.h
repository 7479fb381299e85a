#pragma once

// Format v2's geometry pages on their way from the file to the GPU, in two steps:
//
//  1. ClusterPageIndexer, the page cache's decode stage (cache/PageDecoder.h): on the cache's
//     worker threads, checks the page and keeps it *encoded*, with its table of clusters (where
//     each cluster's bytes are and where its vertices and indices go) in front, so the budget
//     holds pages at about their size in the file and a frame finds a node's clusters without
//     decoding anything:
//
//       CachedPageHeader (32 bytes) | IndexedCluster[clusterCount] | the page's encoded
//       payload (usedBytes, zero-padded to 4) | the page's PageTrailer (16 bytes)
//
//     The trailer stays last, as the cached page access expects of every page it hands out.
//  2. decodeCachedPage(), on the decode stage's threads (GeometryDecodeStage.h), when a page is
//     about to be uploaded: the page's 20-byte vertices and cluster-local u8 indices, which the
//     GPU arena keeps (still compact, drawn indexed). The decoded copy lives only until it is
//     uploaded.
//
// The cached form is this process's own (never on disk).

#include <ff/cache/PageDecoder.h>
#include <ff/runtime/DecodedGeometry.h>
#include <ff/storage/ClusterPage.h>
#include <ff/storage/SceneFormat.h>
#include <ff/storage/Status.h>

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace ff::runtime {

/**
 * Indexes the Geometry pages of a format v2 file on the cache's worker threads (every other
 * page is kept as read): the page's checks, and that the prototype it names has a grid. Safe to
 * call concurrently (the grids are immutable).
 */
class ClusterPageIndexer final : public cache::IPageDecoder {
public:
    /** `grids[p]`: prototype p's position grid (only their number is needed here). */
    explicit ClusterPageIndexer(std::vector<storage::PositionGrid> grids);

    std::size_t maxDecodedBytes(std::uint32_t pageSize) const override;
    /** Errors: Corrupt "page N: cluster page: ..." (the page's checks, an unknown prototype). */
    Status decode(std::uint64_t index, cache::PageBuffer& page) override;

private:
    std::vector<storage::PositionGrid> mGrids;
};

/** A cluster page as the cache keeps it, as the frame reads it (a lookup's payload: trailer cut
 *  off). */
class CachedClusterPage {
public:
    /** Checks that `payload` is a cached cluster page (magic, sizes). Errors: Corrupt. */
    [[nodiscard]] static Result<CachedClusterPage> view(std::span<const std::byte> payload);

    std::uint32_t prototype() const noexcept { return mPrototype; }
    std::span<const storage::IndexedCluster> clusters() const noexcept { return mClusters; }
    /** The page's encoded payload from its first byte: cluster offsets are into it. */
    std::span<const std::byte> encoded() const noexcept { return mEncoded; }
    /** What the whole page decodes to. */
    std::uint32_t vertexCount() const noexcept { return mVertexCount; }
    std::uint32_t indexCount() const noexcept { return mIndexCount; }

    /** Clusters [first, first + count) of the page; empty when they run past its table. */
    std::span<const storage::IndexedCluster>
    clusters(std::uint32_t first, std::uint32_t count) const noexcept {
        if (std::uint64_t{first} + count > mClusters.size())
            return {};
        return mClusters.subspan(first, count);
    }
    /** The clusters a draw names (GeometryDraw's payload, first, count): empty when the payload
     *  is not a cached cluster page or they run past its table. */
    static std::span<const storage::IndexedCluster>
    clustersOf(std::span<const std::byte> payload, std::uint32_t first, std::uint32_t count) {
        const Result<CachedClusterPage> page = view(payload);
        return page ? page->clusters(first, count) : std::span<const storage::IndexedCluster>{};
    }

    /** The clusters of a node's payload (its representation's offset, length, count). */
    [[nodiscard]] Result<storage::ClusterRun>
    run(std::uint32_t offset, std::uint32_t length, std::uint32_t count) const {
        return storage::findClusterRun(mClusters, offset, length, count);
    }

private:
    std::uint32_t mPrototype = 0;
    std::uint32_t mVertexCount = 0;
    std::uint32_t mIndexCount = 0;
    std::span<const storage::IndexedCluster> mClusters;
    std::span<const std::byte> mEncoded;
};

/** Decodes every cluster of a cached page on `grids[page.prototype()]`. Errors: Corrupt (a bad
 *  stream, an unknown prototype, a table that runs past the page, more than `maxBytes` decoded:
 *  storage::maxDecodedClusterBytes of the file's page size). */
[[nodiscard]] Result<DecodedGeometry> decodeCachedPage(
        const CachedClusterPage& page,
        std::span<const storage::PositionGrid> grids,
        std::uint64_t maxBytes);

} // namespace ff::runtime
