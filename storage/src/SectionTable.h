#pragma once

// Rules for the section table in page 0 (FORMAT.md "Section table"), shared by the writer (which
// refuses to commit a table the reader would reject) and the reader.

#include <ff/storage/SceneFormat.h>

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

namespace ff::storage {

/** "Prototypes", "Instances", "Metadata", "Hierarchy", "NodePages" or "unknown". */
const char* sectionTypeName(std::uint32_t type) noexcept;

/** Bytes per item of a record section (Prototypes, Instances, NodePages) in a file of
 *  `formatVersion`; 0 for the others. */
std::size_t sectionRecordSize(std::uint32_t type, std::uint32_t formatVersion) noexcept;

/** Table pages needed for a stream of `byteLength` bytes. */
std::uint64_t sectionPagesFor(std::uint64_t byteLength, std::uint32_t pageSize) noexcept;

/**
 * Checks `sections` for a file of `pageCount` pages of `pageSize` bytes in `formatVersion`
 * (NodePages is a version 2 section): known and distinct
 * types, page ranges inside [1, pageCount), disjoint ranges, byte lengths that fill exactly
 * their pages, item counts matching record sizes. Returns the first problem ("section 1
 * (Instances): ...") or an empty string.
 */
std::string findSectionTableProblem(
        std::span<const SectionEntry> sections,
        std::uint64_t pageCount,
        std::uint32_t pageSize,
        std::uint32_t formatVersion);

} // namespace ff::storage
