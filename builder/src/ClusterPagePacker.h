#pragma once

// Format v2's geometry pages as the builder writes them (storage/FORMAT.md §6.4): node payloads
// of clusters packed into one prototype's cluster pages in the order the nodes come, each page
// filled with a node's clusters before the next opens (one representation per page a node
// reaches). Pages go to the writer as they fill; several packers may write to one writer at
// once (one per octree level of a chunked prototype), so representations name the packer's
// own page numbers, which filePage() turns into the file's once the page is written.

#include <ff/storage/ClusterPage.h>
#include <ff/storage/NodeRecordV2.h>
#include <ff/storage/SceneWriter.h>
#include <ff/storage/Status.h>

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

namespace ff::builder {

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

    /** Writes the open page, if any. */
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
    storage::SceneWriter& mWriter;
    std::uint32_t mPrototype;
    std::optional<storage::ClusterPageWriter> mOpen;
    std::vector<std::uint32_t> mFilePages; ///< per page written, its page in the file
};

} // namespace ff::builder
