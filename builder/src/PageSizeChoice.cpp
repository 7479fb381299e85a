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

} // namespace

std::uint64_t estimatePayloadBytes(const PageSizeInputs& inputs) noexcept {
    std::uint64_t bytes = 0;
    for (const PrototypeCount& p : inputs.prototypes) {
        bytes += p.triangles * sizeof(storage::PackedTriangle) +
                 p.triangles * kNodeBytesPerHundredTriangles / 100;
        bytes += p.triangles > 0 ? p.instances * kBytesPerInstance : 0;
    }
    return bytes;
}

std::uint64_t fixedPartialPages(const PageSizeInputs& inputs) noexcept {
    constexpr std::uint64_t kHeaderAndTables = 4;
    const auto stored = std::count_if(
            inputs.prototypes.begin(), inputs.prototypes.end(), [](const PrototypeCount& p) {
                return p.triangles > 0;
            });
    return kHeaderAndTables + 2 * static_cast<std::uint64_t>(stored);
}

std::uint64_t drawCommands(const PageSizeInputs& inputs, std::uint32_t pageSize) noexcept {
    const std::uint64_t perPage = storage::trianglesPerPage(pageSize);
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
