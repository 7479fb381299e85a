#pragma once

// Format v2's geometry pages as the builder writes them (storage/FORMAT.md §6.4): node payloads
// of clusters packed into one prototype's cluster pages in the order the nodes come (one
// representation per page a node reaches). A few pages stay open at once, and a node's clusters
// go first into the oldest open page they fit, so a page closes only when clusters of the
// nodes after it could not fill it either: the slack a page keeps is what none of them fits,
// not what the next node's first cluster happened to leave (measured below, kOpenPages).
// Pages go to the writer as they close, oldest first; several packers may write to one writer
// at once (one per octree level of a chunked prototype), so representations name the packer's
// own page numbers, which filePage() turns into the file's once the page is written.

#include <ff/storage/ClusterPage.h>
#include <ff/storage/NodeRecordV2.h>
#include <ff/storage/SceneWriter.h>
#include <ff/storage/Status.h>

#include <cstddef>
#include <cstdint>
#include <deque>
#include <span>
#include <vector>

namespace ff::builder {

/** Pages a packer keeps open. Four keep a page's clusters within a few pages of nodes in
 *  their order (a frame reading a node's neighbours reads the same pages). Against one open
 *  page, the files of the scanned models (4 KiB pages, ~1.1 KiB clusters) took 7.17 instead of
 *  7.21 bytes a triangle (skull) and 7.59 instead of 7.84 (demosthenes); with --cluster-nodes
 *  the skull 8.07 instead of 8.23. At 64 KiB pages (terrain, sphere) nothing changed. What is
 *  left at 4 KiB is the clusters' granularity: a page holds three of them, by bytes and by
 *  what they decode to (ClusterPageWriter::fits). */
inline constexpr std::size_t kOpenPages = 4;

/** Not thread-safe. */
class ClusterPagePacker {
public:
    ClusterPagePacker(storage::SceneWriter& writer, std::uint32_t prototype);

    /** Places one node's payload (`count` encoded clusters, back to back) and appends its
     *  representations to `out`, their `page` this packer's page number (from 0).
     *  Errors: the writer's; Internal for a cluster larger than a page. */
    [[nodiscard]] Status
    place(std::span<const std::byte> clusters,
          std::uint32_t count,
          std::vector<storage::RepresentationRecord>& out);

    /** place() for a subtree's stand-in (StandIns.h): its representations are of `kind`
     *  (Clusters: simplified; Splats), flagged kRepresentationStandIn with `error` as their
     *  parameter. */
    [[nodiscard]] Status placeStandIn(
            std::span<const std::byte> clusters,
            std::uint32_t count,
            float error,
            storage::RepresentationKind kind,
            std::vector<storage::RepresentationRecord>& out);

    /** Writes the open pages, if any. */
    [[nodiscard]] Status finish();

    /** Geometry pages written so far. */
    [[nodiscard]] std::uint64_t pages() const noexcept { return mFilePages.size(); }
    /** The file page of this packer's page `local`, once written. */
    [[nodiscard]] std::uint32_t filePage(std::uint32_t local) const { return mFilePages.at(local); }
    /** `r` with its page number the file's (the page must have been written). */
    [[nodiscard]] storage::RepresentationRecord relocated(storage::RepresentationRecord r) const {
        r.page = filePage(r.page);
        return r;
    }

private:
    struct OpenPage {
        storage::ClusterPageWriter writer;
        std::uint32_t local = 0; ///< this packer's number for it
    };

    /** Appends to `page` every cluster of `remaining` that fits, in order, as one run (at most
     *  65,535 clusters), into `out`; keeps the others in `remaining`. */
    [[nodiscard]] Status fill(
            OpenPage& page,
            std::vector<std::span<const std::byte>>& remaining,
            std::vector<storage::RepresentationRecord>& out);
    /** Writes the oldest open page. */
    [[nodiscard]] Status closeOldest();

    storage::SceneWriter& mWriter;
    std::uint32_t mPrototype;
    std::deque<OpenPage> mOpen;            ///< oldest first
    std::uint32_t mOpened = 0;             ///< pages opened so far: the next one's number
    std::vector<std::uint32_t> mFilePages; ///< per page written, its page in the file
};

} // namespace ff::builder
