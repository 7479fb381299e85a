#pragma once

// The decode stage for format v2's geometry pages (storage/ClusterPage.h): what the page cache
// keeps of a cluster page, decoded on its worker threads once for every node on the page, and
// the view the frame reads it through. The decoded form is this process's own (never on disk):
//
//   DecodedPageHeader (32 bytes) | IndexedCluster[clusterCount] | PackedVertex[vertexCount] |
//   u8 indices[indexCount], zero-padded to 4 | the page's PageTrailer (16 bytes)
//
// The trailer stays last, as the cached page access expects of every page it hands out.
// Vertices stay compact (20 bytes, cluster-local u8 indices) for indexed draws.

#include <ff/cache/PageDecoder.h>
#include <ff/storage/ClusterPage.h>
#include <ff/storage/SceneFormat.h>
#include <ff/storage/Status.h>

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace ff::runtime {

/**
 * Decodes the Geometry pages of a format v2 file on the cache's worker threads; every other
 * page is kept as read. Each page's clusters are dequantized on the grid of the prototype its
 * header names. Safe to call concurrently (the grids are immutable).
 */
class ClusterPageDecoder final : public cache::IPageDecoder {
public:
    /** `grids[p]`: prototype p's position grid. */
    explicit ClusterPageDecoder(std::vector<storage::PositionGrid> grids);

    std::size_t maxDecodedBytes(std::uint32_t pageSize) const override;
    /** Errors: Corrupt "page N: cluster page: ..." (the page's checks, an unknown prototype). */
    Status decode(std::uint64_t index, cache::PageBuffer& page) override;

private:
    std::vector<storage::PositionGrid> mGrids;
};

/** A decoded cluster page as the frame reads it (the payload a lookup gives: trailer cut off). */
class DecodedClusterPage {
public:
    /** Checks that `payload` is a decoded cluster page (magic, sizes). Errors: Corrupt. */
    [[nodiscard]] static Result<DecodedClusterPage> view(std::span<const std::byte> payload);

    std::uint32_t prototype() const noexcept { return mPrototype; }
    std::span<const storage::IndexedCluster> clusters() const noexcept { return mClusters; }
    std::span<const storage::PackedVertex> vertices() const noexcept { return mVertices; }
    std::span<const std::uint8_t> indices() const noexcept { return mIndices; }

    /** Clusters [first, first + count) of the page; empty when they run past its table. */
    std::span<const storage::IndexedCluster> clusters(std::uint32_t first, std::uint32_t count) const noexcept {
        if (std::uint64_t{first} + count > mClusters.size())
            return {};
        return mClusters.subspan(first, count);
    }
    /** The clusters a draw names (GeometryDraw's payload, first, count): empty when the payload
     *  is not a decoded cluster page or they run past its table. */
    static std::span<const storage::IndexedCluster>
    clustersOf(std::span<const std::byte> payload, std::uint32_t first, std::uint32_t count) {
        const Result<DecodedClusterPage> page = view(payload);
        return page ? page->clusters(first, count) : std::span<const storage::IndexedCluster>{};
    }

    /** The clusters of a node's payload (its representation's offset, length, count). */
    [[nodiscard]] Result<storage::ClusterRun>
    run(std::uint32_t offset, std::uint32_t length, std::uint32_t count) const {
        return storage::findClusterRun(mClusters, offset, length, count);
    }

private:
    std::uint32_t mPrototype = 0;
    std::span<const storage::IndexedCluster> mClusters;
    std::span<const storage::PackedVertex> mVertices;
    std::span<const std::uint8_t> mIndices;
};

} // namespace ff::runtime
