#include "SubtreeEncoderV2.h"

#include "ClusterPagePacker.h"
#include "ParallelFor.h"

#include <ff/builder/ColorCube.h>
#include <ff/storage/Assert.h>
#include <ff/storage/NodeCellV2.h>
#include <ff/storage/NodePageV2.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <unordered_map>

namespace ff::builder {

namespace {

constexpr std::uint32_t kNone = 0xFFFFFFFFu;

bool isInstance(const BuildNode& node) {
    return node.kind == static_cast<std::uint8_t>(storage::NodeKind::Instance);
}

bool placedElsewhere(const BuildNode& node) {
    return node.placedChildren.has_value() || node.placedTriangles.has_value();
}

std::array<float, 3> toArray(const glm::vec3& v) {
    return {v.x, v.y, v.z};
}

/** The hierarchy as it will be written: reachable nodes breadth first (sibling blocks in
 *  order), with their parents. A placed node's children are elsewhere: not entered. */
struct Tree {
    std::vector<std::uint32_t> order;
    std::vector<std::uint32_t> parent; ///< per node; kNone for the root and unreached nodes
};

Tree breadthFirst(const std::vector<BuildNode>& nodes) {
    Tree tree;
    tree.parent.assign(nodes.size(), kNone);
    tree.order.push_back(0);
    for (std::size_t i = 0; i < tree.order.size(); ++i) {
        const std::uint32_t n = tree.order[i];
        const BuildNode& node = nodes[n];
        if (node.placedChildren)
            continue;
        for (std::uint32_t c = 0; c < node.childCount; ++c) {
            tree.order.push_back(node.firstChild + c);
            tree.parent[node.firstChild + c] = n;
        }
    }
    return tree;
}

storage::NodeBox boxOf(const glm::vec3& min, const glm::vec3& max) {
    return {toArray(min), toArray(max)};
}

std::vector<storage::DecodedNodeV2> decodedNodes(
        const std::vector<BuildNode>& nodes, const Tree& tree, const storage::DecodedNodeV2& rootParent) {
    std::vector<storage::DecodedNodeV2> decoded(nodes.size());
    for (const std::uint32_t n : tree.order) {
        const storage::DecodedNodeV2& parent =
                tree.parent[n] == kNone ? rootParent : decoded[tree.parent[n]];
        storage::NodeV2 record;
        // The box lies inside its parent by construction: quantizing outward cannot fail.
        decoded[n] = placeUnder(
                             record,
                             boxOf(nodes[n].boundsMin, nodes[n].boundsMax),
                             boxOf(nodes[n].cellMin, nodes[n].cellMax),
                             parent)
                             .value();
    }
    return decoded;
}

/** One node's triangles as clusters. */
struct EncodedPayload {
    std::vector<std::byte> bytes;
    ClusterBuildStats stats;
};

/** Encodes `runs[k]` (by position; empty ones are skipped) into `out[k]` on `threads`
 *  threads. */
Status encodePayloads(
        const std::vector<std::span<const storage::PackedTriangle>>& runs,
        const storage::PositionGrid& grid,
        unsigned threads,
        std::vector<EncodedPayload>& out) {
    std::vector<std::size_t> work;
    for (std::size_t k = 0; k < runs.size(); ++k)
        if (!runs[k].empty())
            work.push_back(k);
    return parallelFor(work.size(), threads, [&] {
        return [&, encoder = ClusterEncoder()](std::size_t k) mutable -> Status {
            EncodedPayload& payload = out[work[k]];
            FF_ASSIGN_OR_RETURN(payload.stats, encoder.encode(runs[work[k]], grid, payload.bytes));
            return Status::ok();
        };
    });
}

/** Where a node goes: a page of this subtree (from 0) and a slot in it. */
struct Placement {
    std::uint32_t page = 0;
    std::uint32_t slot = 0;
};

} // namespace

storage::NodeBox boundsInside(
        const std::array<float, 3>& boundsMin,
        const std::array<float, 3>& boundsMax,
        const storage::NodeBox& parent) {
    storage::NodeBox box;
    for (std::size_t a = 0; a < 3; ++a) {
        const float lo = boundsMin[a];
        const float hi = boundsMax[a];
        if (!(lo <= hi) || !std::isfinite(lo) || !std::isfinite(hi)) {
            box.min[a] = box.max[a] = parent.min[a];
            continue;
        }
        // A child's bounds lie inside its parent's by construction (a parent's are the union);
        // the clamp only absorbs float noise of decompositions that recompute them.
        box.min[a] = std::clamp(lo, parent.min[a], parent.max[a]);
        box.max[a] = std::clamp(hi, box.min[a], parent.max[a]);
    }
    return box;
}

Result<storage::DecodedNodeV2> placeUnder(
        storage::NodeV2& record,
        const storage::NodeBox& bounds,
        const storage::NodeBox& cell,
        const storage::DecodedNodeV2& parent) {
    record.bounds = boundsInside(bounds.min, bounds.max, parent.bounds);
    record.flags = static_cast<std::uint8_t>(record.flags & ~storage::kNodeV2OctantCell);
    record.octant = 0;
    if (const std::optional<std::uint8_t> octant = storage::matchingOctant(cell, parent.cell)) {
        record.flags = static_cast<std::uint8_t>(record.flags | storage::kNodeV2OctantCell);
        record.octant = *octant;
    }
    storage::DecodedNodeV2 decoded;
    FF_ASSIGN_OR_RETURN(decoded.bounds, storage::quantizeBoundsOutward(record.bounds, parent.bounds));
    storage::NodeV2 read = record;
    read.bounds = decoded.bounds;
    decoded.cell = storage::cellOfNode(read, parent.cell);
    return decoded;
}

std::vector<storage::DecodedNodeV2>
decodedNodesV2(const std::vector<BuildNode>& nodes, const storage::DecodedNodeV2& rootParent) {
    return decodedNodes(nodes, breadthFirst(nodes), rootParent);
}

Status NodePageTable::writeOpen(storage::SceneWriter& writer) {
    if (mOpen.empty())
        return Status::ok();
    FF_ASSIGN_OR_RETURN(
            const std::uint64_t filePage,
            writer.appendPage(storage::PageType::Nodes, mOpen.bytes()));
    if (filePage > 0xFFFFFFFFull)
        return Status(
                ErrorCode::Unsupported,
                "scene needs more than 2^32 pages; use a larger --page-size");
    mPages.push_back(static_cast<std::uint32_t>(filePage));
    mOpen.clear();
    return Status::ok();
}

Result<SubtreeV2Result> writeSubtreeV2(
        storage::SceneWriter& writer,
        NodePageTable& table,
        std::vector<BuildNode> nodes,
        std::span<const storage::PackedTriangle> triangles,
        const SubtreeV2Input& input) {
    FF_ASSERT(!nodes.empty());
    std::unordered_map<std::uint32_t, const PlacedNodeV2*> placed;
    for (const PlacedNodeV2& p : input.placed)
        placed[p.node] = &p;
    for (std::size_t n = 0; n < nodes.size(); ++n)
        if (placedElsewhere(nodes[n]) && placed.count(static_cast<std::uint32_t>(n)) == 0)
            return Status(ErrorCode::Internal, "a node placed elsewhere without its placement");
    const bool hasGeometry = input.grid != nullptr;
    const Tree tree = breadthFirst(nodes);
    SubtreeV2Result result;

    // ---- geometry: each node's triangles as clusters, breadth first -------------------------
    std::vector<std::uint32_t> firstRep(nodes.size(), 0);
    std::vector<std::uint32_t> repCount(nodes.size(), 0);
    std::vector<storage::RepresentationRecord> reps;
    std::vector<std::uint64_t> ownKept(nodes.size(), 0);
    std::vector<std::uint64_t> ownUnlit(nodes.size(), 0);
    {
        // Clustering is most of the encoding's time: done for every node on input.threads
        // threads first, then packed into pages in the nodes' order (deterministic bytes).
        std::vector<EncodedPayload> encoded(tree.order.size());
        std::vector<EncodedPayload> encodedStandIns(tree.order.size());
        std::vector<float> standInError(tree.order.size(), 0.0f);
        std::vector<storage::RepresentationKind> standInKind(tree.order.size());
        if (hasGeometry) {
            std::vector<std::span<const storage::PackedTriangle>> runs(tree.order.size());
            for (std::size_t i = 0; i < tree.order.size(); ++i) {
                const BuildNode& node = nodes[tree.order[i]];
                if (placed.count(tree.order[i]) == 0 && !isInstance(node))
                    runs[i] = triangles.subspan(node.firstTriangle, node.triangleCount);
            }
            FF_RETURN_IF_ERROR(encodePayloads(runs, *input.grid, input.threads, encoded));
            if (input.standIns.simplified || input.standIns.splatSpacing > 0) {
                std::vector<PlacedSource> sources;
                for (const PlacedNodeV2& p : input.placed)
                    if (p.standInSource.usable)
                        sources.push_back({p.node, &p.standInSource});
                FF_ASSIGN_OR_RETURN(
                        std::vector<std::optional<StandIn>> standIns,
                        buildStandIns(
                                nodes,
                                triangles,
                                *input.grid,
                                sources,
                                input.threads,
                                nullptr,
                                result.standInCounts,
                                {maxStandInTriangles(writer.pageSize()), true},
                                input.standIns));
                std::vector<std::size_t> work;
                for (std::size_t i = 0; i < tree.order.size(); ++i)
                    if (const std::optional<StandIn>& standIn = standIns[tree.order[i]]) {
                        work.push_back(i);
                        standInError[i] = standIn->error;
                        standInKind[i] = representationKindOf(standIn->kind);
                    }
                FF_RETURN_IF_ERROR(parallelFor(work.size(), input.threads, [&] {
                    return [&, encoder = ClusterEncoder()](std::size_t k) mutable -> Status {
                        const std::size_t i = work[k];
                        EncodedPayload& payload = encodedStandIns[i];
                        FF_ASSIGN_OR_RETURN(
                                payload.stats,
                                encodeStandIn(encoder, *standIns[tree.order[i]], *input.grid, payload.bytes));
                        return Status::ok();
                    };
                }));
            }
        }
        ClusterPagePacker packer(writer, input.prototype);
        std::vector<bool> local; // per rep: a page of this packer, to relocate
        for (std::size_t i = 0; i < tree.order.size(); ++i) {
            const std::uint32_t n = tree.order[i];
            const BuildNode& node = nodes[n];
            firstRep[n] = static_cast<std::uint32_t>(reps.size());
            if (const auto p = placed.find(n); p != placed.end()) {
                reps.insert(
                        reps.end(),
                        p->second->representations.begin(),
                        p->second->representations.end());
                local.resize(reps.size(), false);
                ownKept[n] = p->second->storedTriangles;
            } else if (node.triangleCount > 0 && !isInstance(node)) {
                if (!hasGeometry)
                    return Status(
                            ErrorCode::Internal, "triangles in a hierarchy written without a grid");
                const EncodedPayload& payload = encoded[i];
                result.clusters += payload.stats;
                ownKept[n] = payload.stats.trianglesKept;
                ownUnlit[n] = payload.stats.trianglesUnlit;
                FF_RETURN_IF_ERROR(packer.place(
                        payload.bytes, static_cast<std::uint32_t>(payload.stats.clusters), reps));
                local.resize(reps.size(), true);
                encoded[i] = EncodedPayload{}; // its memory back as it goes
            }
            if (const EncodedPayload& standIn = encodedStandIns[i]; standIn.stats.clusters > 0) {
                result.standInClusters += standIn.stats;
                ++result.standIns;
                FF_RETURN_IF_ERROR(packer.placeStandIn(
                        standIn.bytes,
                        static_cast<std::uint32_t>(standIn.stats.clusters),
                        standInError[i],
                        standInKind[i],
                        reps));
                local.resize(reps.size(), true);
                encodedStandIns[i] = EncodedPayload{};
            }
            repCount[n] = static_cast<std::uint32_t>(reps.size()) - firstRep[n];
            if (repCount[n] > 255)
                return Status(
                        ErrorCode::Unsupported,
                        "a node needs more than 255 representations; use a larger --page-size");
        }
        FF_RETURN_IF_ERROR(packer.finish());
        for (std::size_t r = 0; r < reps.size(); ++r)
            if (local[r])
                reps[r] = packer.relocated(reps[r]);
        result.geometryPages = packer.pages();
    }

    // ---- what each node draws at and below it, as stored, and how much of it is unlit ------
    // (an instance's prototype counts as lit: the unlit flag is its own nodes')
    std::vector<double> drawn(nodes.size(), 0.0);
    std::vector<double> unlit(nodes.size(), 0.0);
    for (std::size_t i = tree.order.size(); i-- > 0;) {
        const std::uint32_t n = tree.order[i];
        const BuildNode& node = nodes[n];
        if (const auto p = placed.find(n); p != placed.end()) {
            drawn[n] += p->second->drawnTriangles;
            unlit[n] += p->second->unlitTriangles;
        } else if (isInstance(node)) {
            drawn[n] += static_cast<double>(
                    node.instanceIndex < input.instanceTriangles.size()
                            ? input.instanceTriangles[node.instanceIndex]
                            : 0);
        } else {
            drawn[n] += static_cast<double>(ownKept[n]);
            unlit[n] += static_cast<double>(ownUnlit[n]);
        }
        if (tree.parent[n] != kNone) {
            drawn[tree.parent[n]] += drawn[n];
            unlit[tree.parent[n]] += unlit[n];
        }
    }

    // ---- node pages: whole sibling blocks in breadth-first order -----------------------------
    // pages[0] is the table's open page, which may hold another hierarchy's records already.
    const std::uint32_t slotsPerPage = storage::nodesPerPageV2(writer.pageSize());
    const std::uint64_t payloadBytes = storage::pagePayloadBytes(writer.pageSize());
    std::vector<Placement> placement(nodes.size());
    std::vector<std::vector<std::uint32_t>> pages(1); // nodes per page, slot order
    {
        std::uint64_t pageNodes = table.open().nextSlot();
        std::uint64_t pageReps = table.open().representationCount();
        auto placeBlock = [&](std::uint32_t first, std::uint32_t count) -> Status {
            std::uint64_t blockReps = 0;
            for (std::uint32_t k = 0; k < count; ++k)
                blockReps += repCount[first + k];
            const auto fits = [&](std::uint64_t nodesBefore, std::uint64_t repsBefore) {
                return storage::kNodeRecordV2Size * (nodesBefore + count) +
                               storage::kRepresentationRecordSize * (repsBefore + blockReps) <=
                       payloadBytes;
            };
            if (!fits(pageNodes, pageReps)) {
                if (!fits(0, 0))
                    return Status(
                            ErrorCode::Unsupported,
                            "a sibling block of " + std::to_string(count) + " nodes and " +
                                    std::to_string(blockReps) +
                                    " representations does not fit one page; use a larger "
                                    "--page-size");
                pages.emplace_back();
                pageNodes = 0;
                pageReps = 0;
            }
            for (std::uint32_t k = 0; k < count; ++k) {
                placement[first + k] = {
                        static_cast<std::uint32_t>(pages.size() - 1),
                        static_cast<std::uint32_t>(pageNodes + k)};
                pages.back().push_back(first + k);
            }
            pageNodes += count;
            pageReps += blockReps;
            return Status::ok();
        };
        FF_RETURN_IF_ERROR(placeBlock(0, 1));
        for (const std::uint32_t n : tree.order) {
            const BuildNode& node = nodes[n];
            if (node.childCount > 0 && !node.placedChildren)
                FF_RETURN_IF_ERROR(placeBlock(node.firstChild, node.childCount));
        }
    }
    const std::uint64_t ordinalBase = table.openOrdinal();
    const auto indexOf = [&](std::uint32_t n) -> Result<std::uint32_t> {
        const std::uint64_t index =
                (ordinalBase + placement[n].page) * slotsPerPage + placement[n].slot;
        if (index >= kNone)
            return Status(ErrorCode::Unsupported, "scene needs more than 2^32 node slots");
        return static_cast<std::uint32_t>(index);
    };

    const std::vector<storage::DecodedNodeV2> decoded = decodedNodes(nodes, tree, input.rootParent);
    for (std::size_t p = 0; p < pages.size(); ++p) {
        if (p > 0)
            FF_RETURN_IF_ERROR(table.writeOpen(writer));
        storage::NodePageV2Writer& page = table.open();
        for (const std::uint32_t n : pages[p]) {
            const BuildNode& node = nodes[n];
            const storage::DecodedNodeV2& parent =
                    tree.parent[n] == kNone ? input.rootParent : decoded[tree.parent[n]];
            storage::NodeV2 record;
            record.cube = quantizeCube(node.cube);
            record.subtreeTriangles = static_cast<float>(drawn[n]);
            record.kind =
                    isInstance(node) ? storage::NodeKindV2::Instance : storage::NodeKindV2::Cell;
            record.flags = storage::kNodeV2HasCube;
            FF_RETURN_IF_ERROR(placeUnder(
                                       record,
                                       boxOf(node.boundsMin, node.boundsMax),
                                       boxOf(node.cellMin, node.cellMax),
                                       parent)
                                       .status());
            if (!isInstance(node))
                record.flags = static_cast<std::uint8_t>(record.flags | unlitFlag(drawn[n], unlit[n]));
            if (node.childCount > 0) {
                if (const auto q = placed.find(n); q != placed.end() && node.placedChildren) {
                    record.firstChild = q->second->firstChild;
                } else {
                    FF_ASSIGN_OR_RETURN(record.firstChild, indexOf(node.firstChild));
                }
                record.childCount = static_cast<std::uint8_t>(node.childCount);
                if (node.octreeChildren)
                    record.flags = static_cast<std::uint8_t>(
                            record.flags | storage::kNodeV2OctreeChildren);
            }
            if (isInstance(node))
                record.firstRepresentation = node.instanceIndex;
            const auto own =
                    std::span(reps).subspan(firstRep[n], isInstance(node) ? 0 : repCount[n]);
            FF_ASSIGN_OR_RETURN(const std::uint32_t slot, page.append(record, parent.bounds, own));
            FF_ASSERT(slot == placement[n].slot);
            ++result.nodes;
            result.leafNodes += node.childCount > 0 ? 0 : 1;
            result.maxLevel = std::max<std::uint32_t>(result.maxLevel, node.level);
            result.storedTriangles += ownKept[n];
        }
    }
    result.nodePages = pages.size();
    FF_ASSIGN_OR_RETURN(result.rootNode, indexOf(0));
    return result;
}

} // namespace ff::builder
