#pragma once

// The decode stage of the page cache: what a page becomes between being read and being kept.
// Compact pages (quantized, entropy-coded clusters) are decoded here, on the cache's worker
// threads, never on the thread that draws; the resident set and its budget hold the decoded form.
// The cache knows pages and bytes, not what they mean: a decoder is given by who knows
// (the runtime, for geometry).

#include <ff/storage/Status.h>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>

namespace ff::cache {

/** A page's bytes as the cache holds them: as read (pageSize bytes) or as decoded. */
struct PageBuffer {
    std::unique_ptr<std::byte[]> bytes;
    std::size_t size = 0;

    [[nodiscard]] std::span<const std::byte> view() const noexcept { return {bytes.get(), size}; }
};

/**
 * Turns a page as read into the form kept resident. Called on the cache's worker threads,
 * several pages at once: implementations must be safe to call concurrently.
 */
class IPageDecoder {
public:
    virtual ~IPageDecoder() = default;
    /** The most bytes decode() leaves in a page of `pageSize` bytes: what one read in flight
     *  may hold, and the least budget a cache with this decoder needs. At least pageSize. */
    [[nodiscard]] virtual std::size_t maxDecodedBytes(std::uint32_t pageSize) const = 0;
    /**
     * Replaces `page` (page `index`, read and verified: pageSize bytes) with its resident
     * form, or leaves it as it is (the page is kept as read). The result holds at most
     * maxDecodedBytes(pageSize) bytes. An error fails the page: PageState::Failed with this
     * status, never read again.
     */
    [[nodiscard]] virtual Status decode(std::uint64_t index, PageBuffer& page) = 0;
};

} // namespace ff::cache
