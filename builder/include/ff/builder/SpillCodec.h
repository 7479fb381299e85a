#pragma once

#include <optional>
#include <string_view>

namespace ff::builder {

/** How the builder's temporary spill files (run, chunk and level files) store their items. */
enum class SpillCodec : unsigned char {
    Raw = 0,     ///< as they are in memory
    Compact = 1, ///< meshoptimizer's vertex codec, lossless (a triangle as its three vertices)
};

/** "raw", "compact". */
std::string_view spillCodecName(SpillCodec codec) noexcept;
std::optional<SpillCodec> parseSpillCodec(std::string_view name) noexcept;

} // namespace ff::builder
