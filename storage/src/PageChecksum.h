#pragma once

// The page trailer and its checksum, shared by the writer and the reader so that both agree on
// every byte (FORMAT.md "Page layout").

#include <ff/storage/SceneFormat.h>

#include <xxhash.h>

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>

namespace ff::storage {

/** Bytes of a page covered by its checksum: everything but the checksum field itself. */
constexpr std::size_t checksummedBytes(std::size_t pageSize) noexcept {
    return pageSize - sizeof(std::uint64_t);
}

/** XXH3-64 (seed 0) of the first pageSize - 8 bytes of `page` (a whole page). */
inline std::uint64_t pageChecksum(std::span<const std::byte> page) noexcept {
    return XXH3_64bits(page.data(), checksummedBytes(page.size()));
}

/** Writes the trailer of `page` (a whole page whose payload is already in place). */
inline void sealPage(std::span<std::byte> page, std::uint32_t pageIndex, PageType type) noexcept {
    PageTrailer trailer{};
    trailer.pageIndex = pageIndex;
    trailer.pageType = static_cast<std::uint16_t>(type);
    trailer.magic = kPageTrailerMagic;
    trailer.checksum = 0;
    std::byte* at = page.data() + (page.size() - sizeof(PageTrailer));
    std::memcpy(at, &trailer, sizeof(trailer));
    trailer.checksum = pageChecksum(page);
    std::memcpy(at, &trailer, sizeof(trailer));
}

/** The trailer of `page` (a whole page, at least sizeof(PageTrailer) bytes). */
inline PageTrailer readTrailer(std::span<const std::byte> page) noexcept {
    PageTrailer trailer{};
    std::memcpy(&trailer, page.data() + (page.size() - sizeof(PageTrailer)), sizeof(trailer));
    return trailer;
}

/** "Nodes", "Geometry", ... or "unknown". */
inline const char* pageTypeName(std::uint16_t type) noexcept {
    switch (static_cast<PageType>(type)) {
    case PageType::Header:
        return "Header";
    case PageType::Nodes:
        return "Nodes";
    case PageType::Geometry:
        return "Geometry";
    case PageType::Table:
        return "Table";
    }
    return "unknown";
}

} // namespace ff::storage
