#pragma once

// Format v2's Nodes pages: 48-byte node records in slots from the start of the payload, and the
// representation records of those nodes (20 bytes each) from its end, so a node's page holds
// everything a reader needs to find its payloads: one fetch per node page, as in v1.
// storage/FORMAT.md §5.4 documents the layout.
//
// Free functions over bytes: reading a node checks its record (decodeNodeV2) and that its
// representations lie inside the page, past its own slot.

#include <ff/storage/NodeRecordV2.h>
#include <ff/storage/SceneFormat.h>
#include <ff/storage/Status.h>

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace ff::storage {

/** Payload offset of page-local representation `index` in a payload of `payloadBytes`: the
 *  representations are stored from the payload's end backwards. */
constexpr std::size_t representationOffset(std::size_t payloadBytes, std::uint32_t index) noexcept {
    return payloadBytes - kRepresentationRecordSize * (std::size_t{index} + 1);
}

/** Fills one v2 Nodes page: records from slot 0 on, their representations from the end. */
class NodePageV2Writer {
public:
    explicit NodePageV2Writer(std::uint32_t pageSize);

    /** Whether `nodes` more records with `representations` more representations fit. */
    [[nodiscard]] bool fits(std::uint32_t nodes, std::uint32_t representations) const noexcept;
    /** The slot the next record gets. */
    [[nodiscard]] std::uint32_t nextSlot() const noexcept { return mNodes; }
    [[nodiscard]] std::uint32_t representationCount() const noexcept { return mRepresentations; }
    [[nodiscard]] bool empty() const noexcept { return mNodes == 0; }

    /**
     * Writes `node` (bounds relative to `parent`) into the next slot and returns it. A Cell's
     * `representations` are stored in the page and its firstRepresentation and
     * representationCount set to them; an Instance takes none. Errors: InvalidArgument when it
     * does not fit, for more than 255 representations, or what encodeNodeV2 refuses.
     */
    [[nodiscard]] Result<std::uint32_t>
    append(NodeV2 node,
           const NodeBox& parent,
           std::span<const RepresentationRecord> representations);

    /** The payload as it stands (P - 16 bytes, zero where nothing was written). */
    [[nodiscard]] std::span<const std::byte> bytes() const noexcept { return mBytes; }
    /** Starts the next page. */
    void clear();

private:
    std::vector<std::byte> mBytes;
    std::uint32_t mNodes = 0;
    std::uint32_t mRepresentations = 0;
};

/**
 * Reads the record in `slot` of a v2 Nodes page's `payload` (page `page`, for messages), bounds
 * decoded relative to `parent`, and checks that a Cell's representations lie inside the page
 * past its slot. Errors: Corrupt "page N: node slot S: ...".
 */
[[nodiscard]] Result<NodeV2> readNodeV2(
        std::span<const std::byte> payload,
        std::uint64_t page,
        std::uint32_t slot,
        const NodeBox& parent);

/** Appends the representations of `node` (read by readNodeV2 from this payload) to `out`, each
 *  checked (decodeRepresentation). Errors: Corrupt "page N: ...". */
[[nodiscard]] Status readRepresentationsV2(
        std::span<const std::byte> payload,
        std::uint64_t page,
        const NodeV2& node,
        std::vector<RepresentationRecord>& out);

} // namespace ff::storage
