#pragma once

// Format v2's prototype record: what v1's holds (root, bounds, counts) plus the position grid its
// clusters are quantized on (ClusterCodec.h), which a reader needs before it decodes any of its
// geometry pages. storage/FORMAT.md §4.4 documents every byte; `build --format 2` writes it.

#include <ff/storage/ClusterCodec.h>
#include <ff/storage/NodeRecordV2.h>
#include <ff/storage/Status.h>

#include <cstddef>
#include <cstdint>
#include <span>

namespace ff::storage {

inline constexpr std::size_t kPrototypeRecordV2Size = 64;

/** A prototype as a v2 reader sees it. */
struct PrototypeV2 {
    std::uint32_t rootNode = 0; ///< node index of its hierarchy's root
    NodeBox bounds;             ///< what its root's bounds are relative to
    PositionGrid grid;
    std::uint64_t triangleCount = 0;
    std::uint64_t nodeCount = 0;
};

/** Writes `prototype` into `out` (at least kPrototypeRecordV2Size bytes). InvalidArgument if
 *  the record would not read back (see decodePrototypeV2). */
[[nodiscard]] Status encodePrototypeV2(const PrototypeV2& prototype, std::span<std::byte> out);

/** Reads and checks the record at the start of `bytes`: finite, ordered bounds; a finite grid of
 *  1-31 bits and positive step whose cube holds the bounds; reserved bytes 0. The root's range
 *  is the caller's to check against the file's nodes. Errors: Corrupt ("prototype: ..."). */
[[nodiscard]] Result<PrototypeV2> decodePrototypeV2(std::span<const std::byte> bytes);

} // namespace ff::storage
