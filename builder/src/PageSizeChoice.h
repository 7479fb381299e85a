#pragma once

// `--page-size auto`: the page size is fixed per file, and every file pays for whole pages it
// does not fill (the header page, one page per table section, the last Nodes and Geometry page
// of every prototype). 64 KiB pages suit big scenes (fewer reads, fewer cache entries) but make
// a small model mostly padding (docs/results/model.md). Smaller pages also split a prototype's
// triangles into more runs, and every instance draws each run with a command of its own, so a
// scene of many instances must not get pages so small that its draw commands multiply.

#include <cstdint>
#include <vector>

namespace ff::builder {

/** One prototype as the scan saw it. */
struct PrototypeCount {
    std::uint64_t triangles = 0;
    std::uint64_t instances = 0;
};

/** What the builder knows about a scene once the scan is done. */
struct PageSizeInputs {
    std::vector<PrototypeCount> prototypes; ///< empty ones (no triangles) included
    std::uint32_t formatVersion = 2;        ///< what the file is written as (storage::kFormatVersion*)
};

/** Payload bytes the scene will need, estimated from its counts (triangles, node records,
 *  instance nodes and transforms), before any page is written. */
std::uint64_t estimatePayloadBytes(const PageSizeInputs& inputs) noexcept;

/** Partly filled pages a file has whatever its size: the header, the three table sections, and
 *  a last Nodes and a last Geometry page per prototype with triangles (v2: four table
 *  sections, one last Nodes page shared by all, a last Geometry page per prototype). */
std::uint64_t fixedPartialPages(const PageSizeInputs& inputs) noexcept;

/** Draw commands for drawing every instance whole once: per instance, one per geometry page
 *  its prototype's triangles span. */
std::uint64_t drawCommands(const PageSizeInputs& inputs, std::uint32_t pageSize) noexcept;

/** The share of the file that whole-page padding may take, at most (1/16). */
inline constexpr std::uint64_t kPaddingShareDivisor = 16;
/** Smaller pages may add draw commands up to twice those of kDefaultPageSize pages, or up to
 *  this many. On llvmpipe the molecule's draw time did not move beyond run-to-run noise from
 *  6.5 k to 78 k commands (so < ~1 us each): 4096 commands cost a few milliseconds at most. */
inline constexpr std::uint64_t kDrawCommandAllowance = 4096;

/** The page size: the largest power of two in [kMinPageSize, kDefaultPageSize] whose fixed
 *  partial pages stay within 1/kPaddingShareDivisor of the estimated payload (kMinPageSize if
 *  none does), raised while its draw commands exceed
 *  max(2 x drawCommands(kDefaultPageSize), kDrawCommandAllowance). */
std::uint32_t choosePageSize(const PageSizeInputs& inputs) noexcept;

} // namespace ff::builder
