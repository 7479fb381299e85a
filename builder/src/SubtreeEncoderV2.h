#pragma once

// A hierarchy written as format v2 (storage/FORMAT.md §5.3-5.4, §6.3-6.4): each node's
// triangles encoded into clusters on its prototype's grid and packed into cluster pages, then
// the nodes in 48-byte records with their representations, addressed by node index.

#include "OctreeBuilder.h"
#include "StandIns.h"

#include <ff/builder/ClusterBuild.h>
#include <ff/storage/ClusterCodec.h>
#include <ff/storage/NodeCellV2.h>
#include <ff/storage/NodePageV2.h>
#include <ff/storage/NodeRecordV2.h>
#include <ff/storage/SceneFormat.h>
#include <ff/storage/SceneWriter.h>
#include <ff/storage/Status.h>

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace ff::builder {

/**
 * The file's v2 Nodes pages in node-index order (its NodePages section): node index n is slot
 * n mod nodesPerPageV2 of page pages()[n / nodesPerPageV2]. The last page stays open across
 * hierarchies, so small ones (an instance level, a small prototype) share a page instead of
 * each padding one out; its node indices are known before it is written (they count pages, not
 * file positions).
 */
class NodePageTable {
public:
    explicit NodePageTable(std::uint32_t pageSize)
        : mOpen(pageSize) {}

    /** The page being filled: the next ordinal. */
    [[nodiscard]] storage::NodePageV2Writer& open() noexcept { return mOpen; }
    [[nodiscard]] std::uint64_t openOrdinal() const noexcept { return mPages.size(); }
    /** Appends the open page (if it holds a node) and starts the next. */
    [[nodiscard]] Status writeOpen(storage::SceneWriter& writer);
    /** Pages written, in ordinal order. */
    [[nodiscard]] const std::vector<std::uint32_t>& pages() const noexcept { return mPages; }

private:
    storage::NodePageV2Writer mOpen;
    std::vector<std::uint32_t> mPages;
};

/** A node whose children and own payload were written elsewhere (a chunk's root, whose chunk
 *  went to level regions): what its record needs of them. */
struct PlacedNodeV2 {
    std::uint32_t node = 0;       ///< index in the hierarchy's `nodes`
    std::uint32_t firstChild = 0; ///< node index of its children (the node's childCount of them)
    std::vector<storage::RepresentationRecord> representations; ///< its own payload, final pages
    std::uint64_t storedTriangles = 0;                          ///< its own, as the codec kept them
    double drawnTriangles = 0.0;                                ///< its own and all below it
    double unlitTriangles = 0.0;                                ///< of drawnTriangles
    /** What its subtree gives a stand-in above it (StandIns.h); unusable if none was built. */
    StandInSource standInSource = StandInSource::unusable();
};

/** kNodeV2Unlit for a Cell whose triangles, its own and all below it, are all unlit (none:
 *  no flag); else 0. */
inline std::uint8_t unlitFlag(double drawnTriangles, double unlitTriangles) noexcept {
    return drawnTriangles > 0.0 && unlitTriangles == drawnTriangles
                   ? static_cast<std::uint8_t>(storage::kNodeV2Unlit)
                   : std::uint8_t{0};
}

/**
 * Gives `record` its bounds (`bounds` inside the parent's, boundsInside) and, where the node's
 * cell `cell` is an octant of the parent's (storage::matchingOctant), that octant with
 * kNodeV2OctantCell; returns what the node's children are read against, as a reader decodes it.
 */
[[nodiscard]] Result<storage::DecodedNodeV2> placeUnder(
        storage::NodeV2& record,
        const storage::NodeBox& bounds,
        const storage::NodeBox& cell,
        const storage::DecodedNodeV2& parent);

/** What a v2 hierarchy is written against. */
struct SubtreeV2Input {
    std::uint32_t prototype = 0; ///< whose cluster pages its geometry goes to
    /** The prototype's grid; null for a hierarchy without triangles (the instance level). */
    const storage::PositionGrid* grid = nullptr;
    /** What the root is read against: rootParentV2 of the prototype record's bounds, or of the
     *  header's for the instance level. Its bounds must hold the root's bounds. */
    storage::DecodedNodeV2 rootParent;
    /** Per instance index, the triangles an Instance node draws (its prototype's). */
    std::span<const std::uint64_t> instanceTriangles;
    /** Every node with placedChildren or placedTriangles, resolved. */
    std::span<const PlacedNodeV2> placed;
    /** Threads that cluster the nodes' triangles (the bytes do not depend on it). */
    unsigned threads = 1;
    /** The stand-ins cells get for their subtrees (StandIns.h; needs a grid): none by default. */
    StandInKinds standIns{false, 0};
};

struct SubtreeV2Result {
    std::uint32_t rootNode = 0; ///< node index
    std::uint64_t nodes = 0;
    std::uint64_t leafNodes = 0;
    std::uint64_t storedTriangles = 0; ///< kept by the codec (those quantization collapsed are not)
    std::uint64_t geometryPages = 0;
    std::uint64_t nodePages = 0; ///< pages its records reached (a shared one counted)
    std::uint32_t maxLevel = 0;
    ClusterBuildStats clusters; ///< the nodes' own triangles
    std::uint64_t standIns = 0;
    ClusterBuildStats standInClusters;
    StandInCounts standInCounts;
};

/**
 * What each reachable node of `nodes` decodes to in v2 (bounds relative to its parent's decoded
 * bounds, cell from its parent's cell; the root's against `rootParent`), as writeSubtreeV2
 * stores them: what the records a chunk's root has below it (written before it) are read
 * against. Nodes not reached are left empty.
 */
std::vector<storage::DecodedNodeV2>
decodedNodesV2(const std::vector<BuildNode>& nodes, const storage::DecodedNodeV2& rootParent);

/** The node's bounds as a box inside `parent`, as a v2 record is given them (float noise of a
 *  recomputed union clamped; an empty node at the parent's min corner). */
storage::NodeBox boundsInside(
        const std::array<float, 3>& boundsMin,
        const std::array<float, 3>& boundsMax,
        const storage::NodeBox& parent);

/**
 * Writes the hierarchy `nodes` (nodes[0] the root, children contiguous and after their parents;
 * the nodes with placedChildren or placedTriangles resolved in input.placed) over `triangles`
 * (each node's own run at [firstTriangle, +triangleCount); its leaves shaped for format 2
 * already, shapeLeavesV2): geometry pages first, in the nodes' breadth-first
 * order, then node records of whole sibling blocks in the same order into `table`'s pages
 * (from its open page on; the last is left open), each page's records with their
 * representations. Deterministic.
 */
[[nodiscard]] Result<SubtreeV2Result> writeSubtreeV2(
        storage::SceneWriter& writer,
        NodePageTable& table,
        std::vector<BuildNode> nodes,
        std::span<const storage::PackedTriangle> triangles,
        const SubtreeV2Input& input);

} // namespace ff::builder
