#pragma once

// The integrity check of one scene-file page, for readers that fetch pages themselves (the page
// cache reads with pread rather than through SceneFile's mapping). SceneFile uses the same
// function, so both agree on every byte (FORMAT.md "Page layout").

#include <ff/storage/Status.h>

#include <cstddef>
#include <cstdint>
#include <span>

namespace ff::storage {

/**
 * Checks one whole page of a scene file: trailer magic, XXH3-64 checksum (FORMAT.md), and that
 * the trailer names page `index` (a page written to the wrong place). The page type is left to
 * the caller. `page` must be a whole page (the file's page size, at least 16 bytes: a
 * precondition, asserted). Errors: Corrupt, with a message starting "page <index>: ".
 * Pure: safe to call from any number of threads at once.
 */
[[nodiscard]] Status verifyPageBytes(std::span<const std::byte> page, std::uint64_t index);

} // namespace ff::storage
