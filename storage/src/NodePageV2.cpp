#include "ReaderChecks.h"

#include <ff/storage/NodePageV2.h>

#include <string>

namespace ff::storage {

using detail::corrupt;

NodePageV2Writer::NodePageV2Writer(std::uint32_t pageSize)
    : mBytes(pagePayloadBytes(pageSize)) {}

bool NodePageV2Writer::fits(std::uint32_t nodes, std::uint32_t representations) const noexcept {
    const std::uint64_t used =
            kNodeRecordV2Size * (std::uint64_t{mNodes} + nodes) +
            kRepresentationRecordSize * (std::uint64_t{mRepresentations} + representations);
    return used <= mBytes.size();
}

Result<std::uint32_t> NodePageV2Writer::append(
        NodeV2 node, const NodeBox& parent, std::span<const RepresentationRecord> representations) {
    const bool cell = node.kind == NodeKindV2::Cell;
    if (!cell && !representations.empty())
        return Status(ErrorCode::InvalidArgument, "an instance node takes no representations");
    if (representations.size() > 255)
        return Status(ErrorCode::InvalidArgument, "more than 255 representations for one node");
    const auto count = static_cast<std::uint32_t>(representations.size());
    if (!fits(1, count))
        return Status(
                ErrorCode::InvalidArgument, "the node and its representations do not fit the page");
    if (cell) {
        // Listed from the end backwards, the node's run is ascending page-local indices.
        node.firstRepresentation = mRepresentations;
        node.representationCount = static_cast<std::uint8_t>(count);
        for (std::uint32_t i = 0; i < count; ++i) {
            const std::size_t at = representationOffset(mBytes.size(), mRepresentations + i);
            FF_RETURN_IF_ERROR(encodeRepresentation(
                    representations[i], std::span(mBytes).subspan(at, kRepresentationRecordSize)));
        }
    }
    FF_RETURN_IF_ERROR(encodeNodeV2(
            node,
            parent,
            std::span(mBytes).subspan(std::size_t{mNodes} * kNodeRecordV2Size, kNodeRecordV2Size)));
    mRepresentations += cell ? count : 0;
    return mNodes++;
}

void NodePageV2Writer::clear() {
    std::fill(mBytes.begin(), mBytes.end(), std::byte{0});
    mNodes = 0;
    mRepresentations = 0;
}

Result<NodeV2> readNodeV2(
        std::span<const std::byte> payload,
        std::uint64_t page,
        std::uint32_t slot,
        const NodeBox& parent) {
    const auto at = [slot] { return "node slot " + std::to_string(slot) + ": "; };
    if ((std::uint64_t{slot} + 1) * kNodeRecordV2Size > payload.size())
        return corrupt(
                page,
                at() + "outside the page (" + std::to_string(payload.size() / kNodeRecordV2Size) +
                        " slots)");
    Result<NodeV2> node =
            decodeNodeV2(payload.subspan(std::size_t{slot} * kNodeRecordV2Size), parent);
    if (!node)
        return corrupt(page, at() + node.status().message());
    if (node->kind == NodeKindV2::Cell && node->representationCount > 0) {
        // The representations end at firstRepresentation + count counted from the end, and
        // must not reach back into the node's own slot.
        const std::uint64_t reach =
                kRepresentationRecordSize *
                (std::uint64_t{node->firstRepresentation} + node->representationCount);
        if (reach + (std::uint64_t{slot} + 1) * kNodeRecordV2Size > payload.size())
            return corrupt(
                    page,
                    at() + "representations [" + std::to_string(node->firstRepresentation) + ", +" +
                            std::to_string(node->representationCount) + ") overlap the node slots");
    }
    return node;
}

Status readRepresentationsV2(
        std::span<const std::byte> payload,
        std::uint64_t page,
        const NodeV2& node,
        std::vector<RepresentationRecord>& out) {
    if (node.kind != NodeKindV2::Cell || node.representationCount == 0)
        return Status::ok(); // readNodeV2's rule: no representations, nothing to place
    const std::uint64_t reach =
            kRepresentationRecordSize *
            (std::uint64_t{node.firstRepresentation} + node.representationCount);
    if (reach > payload.size())
        return corrupt(page, "representations outside the page");
    for (std::uint32_t i = 0; i < node.representationCount; ++i) {
        const std::size_t at = representationOffset(payload.size(), node.firstRepresentation + i);
        Result<RepresentationRecord> r =
                decodeRepresentation(payload.subspan(at, kRepresentationRecordSize));
        if (!r)
            return corrupt(
                    page,
                    "representation " + std::to_string(node.firstRepresentation + i) + ": " +
                            r.status().message());
        out.push_back(*r);
    }
    return Status::ok();
}

} // namespace ff::storage
