#pragma once

// Page access, frame layer: what one frame sees of pages (Ready, Pending or Failed, never a
// wait), over the memory map (MappedPageAccess) or the page cache (src/CachedPageAccess.h).

#include <ff/storage/SceneFile.h>
#include <ff/storage/SceneFormat.h>
#include <ff/storage/Status.h>

#include <cstdint>
#include <span>
#include <unordered_map>

namespace ff::runtime {

enum class PageAvailability {
    Ready,   ///< the payload can be used this frame
    Pending, ///< not resident yet; it has been asked for
    Failed,  ///< unreadable or corrupt; `failure` says why (and stays valid)
};

struct PageLookup {
    PageAvailability availability = PageAvailability::Pending;
    /** Ready: the page's payload, its trailer cut off: pagePayloadBytes(pageSize) bytes as
     *  read, or what the cache's decoder made of them. */
    std::span<const std::byte> payload;
    const Status* failure = nullptr;    ///< Failed: the reason, owned by the IPageAccess
};

/** Failures are remembered per (page, expected type): a corrupt reference that expects the
 *  wrong type of a good page must not make that page unusable for correct references. */
inline std::uint64_t failureKey(std::uint64_t page, storage::PageType type) {
    return (page << 3) | static_cast<std::uint64_t>(type);
}

/**
 * How a frame reaches scene-file pages. Selection never waits: a page that is not Ready makes it
 * draw something coarser that is, and the lookup itself asks for the page with the given
 * priority (larger = sooner; selection passes projected size in pixels).
 *
 * Main thread only. Payloads stay valid until the next beginFrame().
 */
class IPageAccess {
public:
    virtual ~IPageAccess() = default;
    virtual void beginFrame() {}
    [[nodiscard]] virtual PageLookup lookup(std::uint64_t page, storage::PageType type, float priority) = 0;
    virtual void endFrame() {}
};

/** Every page at once through the scene file's memory map: the synchronous mode. */
class MappedPageAccess final : public IPageAccess {
public:
    explicit MappedPageAccess(const storage::SceneFile& scene) : mScene(scene) {}
    [[nodiscard]] PageLookup lookup(std::uint64_t page, storage::PageType type, float priority) override;

private:
    const storage::SceneFile& mScene;
    std::unordered_map<std::uint64_t, Status> mFailures;
};

} // namespace ff::runtime
