#include "PageChecksum.h"

#include <ff/storage/PageCheck.h>

#include <cstdio>
#include <string>

namespace ff::storage {

namespace {

std::string hex(std::uint64_t value) {
    char text[24];
    std::snprintf(text, sizeof(text), "0x%llx", static_cast<unsigned long long>(value));
    return text;
}

Status corrupt(std::uint64_t page, const std::string& what) {
    return {ErrorCode::Corrupt, "page " + std::to_string(page) + ": " + what};
}

} // namespace

Status verifyPageBytes(std::span<const std::byte> page, std::uint64_t index) {
    FF_ASSERT(page.size() >= sizeof(PageTrailer));
    const PageTrailer trailer = readTrailer(page);
    if (trailer.magic != kPageTrailerMagic)
        return corrupt(
                index,
                "bad trailer magic " + hex(trailer.magic) + " (expected " + hex(kPageTrailerMagic) +
                        ")");
    const std::uint64_t computed = pageChecksum(page);
    if (trailer.checksum != computed)
        return corrupt(
                index,
                "checksum mismatch (stored " + hex(trailer.checksum) + ", computed " +
                        hex(computed) + ")");
    if (trailer.pageIndex != index)
        return corrupt(
                index,
                "trailer names page " + std::to_string(trailer.pageIndex) +
                        " (page written to the wrong place)");
    return Status::ok();
}

} // namespace ff::storage
