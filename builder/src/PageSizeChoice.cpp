#include "PageSizeChoice.h"

#include <ff/storage/SceneFormat.h>

#include <algorithm>

namespace ff::builder {

namespace {

// Measured on the scenes of docs/results/model.md: 0.08-0.14 nodes per stored triangle for
// single meshes (0.15 taken), each a 96-byte record; an instance is a 96-byte node plus a 56-byte
// transform, and the instance level above them adds about one cell per seven instances.
constexpr std::uint64_t kNodeBytesPerHundredTriangles = 15 * sizeof(storage::NodeRecord);
constexpr std::uint64_t kBytesPerInstance = sizeof(storage::NodeRecord) +
                                            sizeof(storage::InstanceRecord) +
                                            sizeof(storage::NodeRecord) / 7;

// Format 2, measured on built files (docs/results "Compact geometry"): 6.6-8.8 bytes of
// cluster pages per triangle on the terrain and the scanned models (8 taken), and about one
// 48-byte node per thousand triangles (0.1 byte); an instance is a 48-byte node, its transform
// and a seventh of a cell above it.
constexpr std::uint64_t kV2BytesPerTriangle = 8;
constexpr std::uint64_t kV2BytesPerInstance = 48 + sizeof(storage::InstanceRecord) + 48 / 7;

bool isV2(const PageSizeInputs& inputs) noexcept {
    return inputs.formatVersion == storage::kFormatVersion2;
}

/** Triangles one geometry page holds, about. */
std::uint64_t trianglesPerGeometryPage(const PageSizeInputs& inputs, std::uint32_t pageSize) noexcept {
    return isV2(inputs) ? storage::pagePayloadBytes(pageSize) / kV2BytesPerTriangle
                        : storage::trianglesPerPage(pageSize);
}

} // namespace

std::uint64_t estimatePayloadBytes(const PageSizeInputs& inputs) noexcept {
    std::uint64_t bytes = 0;
    if (isV2(inputs)) {
        for (const PrototypeCount& p : inputs.prototypes)
            bytes += p.triangles * kV2BytesPerTriangle + (p.triangles > 0 ? p.instances * kV2BytesPerInstance : 0);
        return bytes;
    }
    for (const PrototypeCount& p : inputs.prototypes) {
        bytes += p.triangles * sizeof(storage::PackedTriangle) +
                 p.triangles * kNodeBytesPerHundredTriangles / 100;
        bytes += p.triangles > 0 ? p.instances * kBytesPerInstance : 0;
    }
    return bytes;
}

std::uint64_t fixedPartialPages(const PageSizeInputs& inputs) noexcept {
    const auto stored = static_cast<std::uint64_t>(std::count_if(
            inputs.prototypes.begin(), inputs.prototypes.end(), [](const PrototypeCount& p) {
                return p.triangles > 0;
            }));
    // v2: prototypes share node pages (one partial page in all) and its tables are four.
    if (isV2(inputs))
        return 5 + 1 + stored;
    constexpr std::uint64_t kHeaderAndTables = 4;
    return kHeaderAndTables + 2 * stored;
}

std::uint64_t drawCommands(const PageSizeInputs& inputs, std::uint32_t pageSize) noexcept {
    const std::uint64_t perPage = trianglesPerGeometryPage(inputs, pageSize);
    std::uint64_t commands = 0;
    for (const PrototypeCount& p : inputs.prototypes)
        commands += p.instances * ((p.triangles + perPage - 1) / perPage);
    return commands;
}

std::uint32_t choosePageSize(const PageSizeInputs& inputs) noexcept {
    const std::uint64_t allowedPadding = estimatePayloadBytes(inputs) / kPaddingShareDivisor;
    const std::uint64_t partialPages = fixedPartialPages(inputs);
    std::uint32_t pageSize = storage::kDefaultPageSize;
    while (pageSize > storage::kMinPageSize && partialPages * pageSize > allowedPadding)
        pageSize /= 2;
    const std::uint64_t allowedCommands =
            std::max(2 * drawCommands(inputs, storage::kDefaultPageSize), kDrawCommandAllowance);
    while (pageSize < storage::kDefaultPageSize && drawCommands(inputs, pageSize) > allowedCommands)
        pageSize *= 2;
    return pageSize;
}

} // namespace ff::builder
