#pragma once

// Where a scene file's pages come from, and how their bytes are held. Everything above the
// storage layer reads pages through an IPageSource: the local file (SceneFile's mapping,
// cache::ScenePageSource's pread), and later a range server or object storage, which then adds
// a source, not a rewrite. The scene index (header and tables, SceneIndex.h) is read through
// the same interface.

#include <ff/storage/Status.h>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <utility>

namespace ff::storage {

/**
 * One page's bytes, held readable for as long as the pin lives: bytes() stays valid and
 * unchanged until the pin is destroyed or reset(), whatever else happens to whoever handed it
 * out (a page cache does not evict a pinned page; a source's buffer is owned by the pin).
 * Move-only; an empty pin holds nothing. A pin may be released on any thread.
 */
class PagePin {
public:
    PagePin() = default;
    /** `holder` keeps `bytes` alive; null where they outlive every pin anyway (a mapping that
     *  lives as long as its file object). */
    PagePin(std::span<const std::byte> bytes, std::shared_ptr<const void> holder) noexcept
        : mBytes(bytes)
        , mHolder(std::move(holder)) {}

    PagePin(PagePin&& other) noexcept
        : mBytes(std::exchange(other.mBytes, {}))
        , mHolder(std::move(other.mHolder)) {}
    PagePin& operator=(PagePin&& other) noexcept {
        mBytes = std::exchange(other.mBytes, {});
        mHolder = std::move(other.mHolder);
        return *this;
    }
    PagePin(const PagePin&) = delete;
    PagePin& operator=(const PagePin&) = delete;

    /** The whole page (pageSize bytes, trailer included). */
    [[nodiscard]] std::span<const std::byte> bytes() const noexcept { return mBytes; }
    [[nodiscard]] bool empty() const noexcept { return mBytes.empty(); }
    void reset() noexcept {
        mBytes = {};
        mHolder.reset();
    }

private:
    std::span<const std::byte> mBytes;
    std::shared_ptr<const void> mHolder;
};

/** Where pages come from. Implementations must be safe to call from several threads at once. */
class IPageSource {
public:
    virtual ~IPageSource() = default;
    virtual std::uint32_t pageSize() const = 0;
    virtual std::uint64_t pageCount() const = 0;
    /** Reads and verifies page `index` into `out` (pageSize bytes): trailer, checksum and the
     *  page's own index (verifyPageBytes), not its type. Errors: Corrupt "page N: ...",
     *  IoError. `out` holds garbage after an error. */
    [[nodiscard]] virtual Status readPage(std::uint64_t index, std::span<std::byte> out) = 0;
    /** Page `index`, verified as readPage() verifies it, held by a pin. The default reads it
     *  into a buffer the pin owns; a source whose pages are in memory already hands out a
     *  view of them. */
    [[nodiscard]] virtual Result<PagePin> pinPage(std::uint64_t index);
};

} // namespace ff::storage
