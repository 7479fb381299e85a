#include "ReaderChecks.h"

#include <ff/storage/ClusterPage.h>
#include <ff/storage/HierarchyCheck.h>
#include <ff/storage/NodePageV2.h>

#include <algorithm>
#include <deque>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <vector>

namespace ff::storage {

using detail::checkType;
using detail::corrupt;
using detail::maskOf;

namespace {

constexpr std::int64_t kInstanceLevel = -1;

/** A node still to visit, with what it is read against. */
struct Pending {
    std::uint32_t node = 0;
    NodeBox parent;
    std::int64_t prototype = kInstanceLevel; ///< whose hierarchy; its grid decodes the clusters
};

/** The cluster pages met so far: each indexed and decoded when first met; the indices of the
 *  last kHeldPages kept for the representations that follow (a walk meets a page's nodes close
 *  together), so memory stays bounded whatever the file (a 10^9-triangle terrain has 5 M
 *  clusters). A page met again after its index went is indexed again, not decoded again. */
class ClusterPages {
public:
    ClusterPages(const SceneIndex& index, IPageSource& source)
        : mIndex(index)
        , mSource(source) {}

    /** What a run of clusters holds. */
    struct RunCounts {
        std::uint64_t triangles = 0;
        std::uint64_t points = 0; ///< vertices of point clusters (splats)
    };

    /** The run `r` names, checked: a cluster page of `prototype`, whole clusters. */
    Result<RunCounts> countsOf(const RepresentationRecord& r, std::uint32_t prototype) {
        if (r.page == 0 || r.page >= mIndex.pageCount())
            return corrupt(r.page, "a representation names a page outside the file");
        auto found = mPages.find(r.page);
        if (found == mPages.end()) {
            const bool seen = mDecoded.count(r.page) != 0;
            FF_ASSIGN_OR_RETURN(ClusterPageIndex page, indexPage(r.page, !seen));
            mDecoded.insert(r.page);
            if (mHeld.size() == kHeldPages) {
                mPages.erase(mHeld.front());
                mHeld.pop_front();
            }
            mHeld.push_back(r.page);
            found = mPages.emplace(r.page, std::move(page)).first;
        }
        const ClusterPageIndex& page = found->second;
        if (page.prototype != prototype)
            return corrupt(
                    r.page,
                    "clusters of prototype " + std::to_string(page.prototype) +
                            " named by a node of prototype " + std::to_string(prototype));
        Result<ClusterRun> run = findClusterRun(page.clusters, r.offset, r.length, r.count);
        if (!run)
            return corrupt(r.page, run.status().message());
        RunCounts counts;
        for (std::uint32_t c = 0; c < run->count; ++c) {
            const ClusterInfo& info = page.clusters[run->first + c].info;
            counts.triangles += info.triangleCount;
            counts.points += info.points() ? info.vertexCount : 0;
        }
        clusters += run->count;
        return counts;
    }

    std::uint64_t clusters = 0;
    [[nodiscard]] std::uint64_t pages() const noexcept { return mDecoded.size(); }

private:
    static constexpr std::size_t kHeldPages = 256;

    Result<ClusterPageIndex> indexPage(std::uint64_t pageIndex, bool decode) {
        FF_ASSIGN_OR_RETURN(const PagePin pin, mSource.pinPage(pageIndex));
        FF_RETURN_IF_ERROR(checkType(
                readTrailer(pin.bytes()).pageType, pageIndex, maskOf(PageType::Geometry)));
        const auto payload = pin.bytes().first(pagePayloadBytes(mIndex.pageSize()));
        Result<ClusterPageIndex> page = indexClusterPage(payload, mIndex.pageSize());
        if (!page)
            return corrupt(pageIndex, page.status().message());
        if (page->prototype >= mIndex.prototypesV2().size())
            return corrupt(
                    pageIndex,
                    "clusters of prototype " + std::to_string(page->prototype) + ", the file has " +
                            std::to_string(mIndex.prototypesV2().size()));
        if (!decode)
            return page;
        // Decoded once here, so a stream that indexes but does not decode is found too.
        std::vector<PackedVertex> vertices(page->vertexCount);
        std::vector<std::uint8_t> indices(page->indexCount);
        const Status decoded = decodeClusterPage(
                payload, *page, mIndex.prototypesV2()[page->prototype].grid, vertices, indices);
        if (!decoded.isOk())
            return corrupt(pageIndex, decoded.message());
        // Indices only: the summary needs the cluster table, not the decoded bytes.
        return page;
    }

    const SceneIndex& mIndex;
    IPageSource& mSource;
    std::unordered_map<std::uint64_t, ClusterPageIndex> mPages; ///< the held indices
    std::deque<std::uint64_t> mHeld;                            ///< their pages, oldest first
    std::unordered_set<std::uint64_t> mDecoded;                 ///< every page met (8 bytes each)
};

} // namespace

Result<HierarchySummary> checkHierarchyV2(
        const SceneIndex& index,
        IPageSource& source,
        const std::function<void(std::uint64_t done, std::uint64_t total)>& progress) {
    if (index.formatVersion() != kFormatVersion2)
        return Status(ErrorCode::InvalidArgument, "checkHierarchyV2 reads version 2 files");
    const FileHeader& header = index.header();
    const std::uint64_t slots = index.nodeSlotCount();
    std::vector<bool> reached(static_cast<std::size_t>(slots), false);
    std::vector<std::uint64_t> nodesOf(index.prototypesV2().size(), 0);
    std::vector<std::uint64_t> trianglesOf(index.prototypesV2().size(), 0);

    std::deque<Pending> pending;
    if ((header.flags & kFileV2HasRoot) != 0)
        pending.push_back(
                {header.root.page, NodeBox{header.boundsMin, header.boundsMax}, kInstanceLevel});
    for (std::size_t p = 0; p < index.prototypesV2().size(); ++p) {
        const PrototypeV2& prototype = index.prototypesV2()[p];
        pending.push_back({prototype.rootNode, prototype.bounds, static_cast<std::int64_t>(p)});
    }

    HierarchySummary summary;
    ClusterPages clusterPages(index, source);
    std::vector<RepresentationRecord> representations;
    std::uint64_t heldPage = 0;
    PagePin held; // consecutive nodes mostly share a page
    while (!pending.empty()) {
        const Pending at = pending.front();
        pending.pop_front();
        FF_ASSIGN_OR_RETURN(const NodeRef where, index.nodeLocation(at.node));
        if (reached[at.node])
            return corrupt(
                    where.page,
                    "node slot " + std::to_string(where.slot) +
                            ": reached twice (a cycle or shared children)");
        reached[at.node] = true;
        if (held.empty() || heldPage != where.page) {
            FF_ASSIGN_OR_RETURN(held, source.pinPage(where.page));
            FF_RETURN_IF_ERROR(checkType(
                    readTrailer(held.bytes()).pageType, where.page, maskOf(PageType::Nodes)));
            heldPage = where.page;
        }
        const auto payload = held.bytes().first(pagePayloadBytes(index.pageSize()));
        FF_ASSIGN_OR_RETURN(
                const NodeV2 node, readNodeV2(payload, where.page, where.slot, at.parent));
        ++summary.nodes;
        if (at.prototype >= 0)
            ++nodesOf[static_cast<std::size_t>(at.prototype)];
        const std::string slot = "node slot " + std::to_string(where.slot) + ": ";

        if (node.kind == NodeKindV2::Instance) {
            if (at.prototype != kInstanceLevel)
                return corrupt(where.page, slot + "an instance inside a prototype");
            if (node.firstRepresentation >= index.instances().size())
                return corrupt(
                        where.page,
                        slot + "instance " + std::to_string(node.firstRepresentation) +
                                " out of range");
        } else {
            representations.clear();
            FF_RETURN_IF_ERROR(readRepresentationsV2(payload, where.page, node, representations));
            if (!representations.empty() && at.prototype == kInstanceLevel)
                return corrupt(where.page, slot + "the instance level holds no payloads");
            bool simplifiedSeen = false; // a stand-in spanning pages is a representation a page
            bool splatsSeen = false;
            for (const RepresentationRecord& r : representations) {
                const bool splats = r.kind == RepresentationKind::Splats;
                if (r.kind != RepresentationKind::Clusters && !splats)
                    return corrupt(
                            where.page, slot + "a payload kind this version does not define");
                FF_ASSIGN_OR_RETURN(
                        const auto counts,
                        clusterPages.countsOf(r, static_cast<std::uint32_t>(at.prototype)));
                if (!splats && counts.points > 0)
                    return corrupt(where.page, slot + "point clusters in a payload of triangles");
                ++summary.representations;
                // A stand-in is a copy of what is below: not stored triangles.
                if (splats) {
                    summary.splatSets += splatsSeen ? 0 : 1;
                    splatsSeen = true;
                    summary.splats += counts.points;
                    summary.splatTriangles += counts.triangles;
                } else if (isStandIn(r)) {
                    summary.standIns += simplifiedSeen ? 0 : 1;
                    simplifiedSeen = true;
                    summary.standInTriangles += counts.triangles;
                } else {
                    trianglesOf[static_cast<std::size_t>(at.prototype)] += counts.triangles;
                }
            }
        }
        if (node.childCount > 0) {
            // In 64 bits: node indices are 32-bit, a garbage one near 2^32 must not wrap.
            if (std::uint64_t{node.firstChild} + node.childCount >
                std::min<std::uint64_t>(slots, 0xFFFFFFFFull))
                return corrupt(where.page, slot + "children outside the node slots");
            // Children sit in one page: the first and last must be on the same one.
            FF_ASSIGN_OR_RETURN(const NodeRef first, index.nodeLocation(node.firstChild));
            FF_ASSIGN_OR_RETURN(
                    const NodeRef last, index.nodeLocation(node.firstChild + node.childCount - 1u));
            if (first.page != last.page)
                return corrupt(where.page, slot + "children cross a page end");
            for (std::uint32_t c = 0; c < node.childCount; ++c)
                pending.push_back({node.firstChild + c, node.bounds, at.prototype});
        }
        if (progress && summary.nodes % 4096 == 0)
            progress(summary.nodes, slots);
    }

    for (std::size_t p = 0; p < index.prototypesV2().size(); ++p) {
        const PrototypeV2& prototype = index.prototypesV2()[p];
        if (nodesOf[p] != prototype.nodeCount || trianglesOf[p] != prototype.triangleCount)
            return corrupt(
                    0,
                    "prototype " + std::to_string(p) + " states " +
                            std::to_string(prototype.nodeCount) + " nodes and " +
                            std::to_string(prototype.triangleCount) +
                            " triangles, its hierarchy holds " + std::to_string(nodesOf[p]) +
                            " and " + std::to_string(trianglesOf[p]));
        summary.triangles += trianglesOf[p];
    }
    if (summary.nodes != header.nodeCount || summary.triangles != header.storedTriangles)
        return corrupt(
                0,
                "the header states " + std::to_string(header.nodeCount) + " nodes and " +
                        std::to_string(header.storedTriangles) +
                        " stored triangles, the hierarchies hold " + std::to_string(summary.nodes) +
                        " and " + std::to_string(summary.triangles));
    summary.clusters = clusterPages.clusters;
    summary.clusterPages = clusterPages.pages();
    if (progress)
        progress(summary.nodes, slots);
    return summary;
}

} // namespace ff::storage
