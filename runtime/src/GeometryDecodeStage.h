#pragma once

// The decode stage between the page cache and the GPU arena, for format v2 (DESIGN.md's
// "decode" stage, moved behind the cache so the budget holds pages encoded):
//
//   main thread:     beginFrame() -> prepare(page) for each page the frame would upload: a
//                    decoded page may be uploaded now (decoded(), then uploaded()); one that is
//                    not is pinned in the cache and queued -> the renderer draws its cell
//                    coarser this frame. uploaded() frees a decoded page at once.
//   decode threads:  take the oldest queued page, decode its pinned cached bytes
//                    (CachedClusterPage.h), release the pin, hand the result back.
//   next beginFrame: finished decodes become ready (so answers hold for a whole frame); ready
//                    pages not asked for in the frame before are freed, queued ones not asked
//                    for again are cancelled.
//
// Memory: pages queued, decoding or decoded at once are at most `capacity`, so the decoded
// bytes held outside the cache's budget are at most capacity x maxDecodedClusterBytes; queued
// pages hold a cache pin until they are decoded (pins count in the cache's budget).

#include "CachedClusterPage.h"

#include <ff/cache/PageCache.h>
#include <ff/runtime/DecodedGeometry.h>
#include <ff/storage/Status.h>

#include <cstdint>
#include <memory>
#include <vector>

namespace ff::runtime {

struct DecodeStageOptions {
    unsigned threads = 2;
    /** Pages queued, being decoded, or decoded and not yet uploaded, at most (>= 1): what a
     *  frame can upload at most, and what the decode threads work ahead on. Twice replay's and
     *  view's default --uploads-per-frame (64 installs): one frame's uploads while the next
     *  frame's are decoded. */
    std::uint32_t capacity = 128;
};

/** Counters since creation, plus what is held now. */
struct DecodeStageStats {
    std::uint64_t requested = 0;    ///< pages queued for decoding
    std::uint64_t decoded = 0;      ///< decodes finished and made ready
    std::uint64_t decodedBytes = 0; ///< what they decoded to
    std::uint64_t cancelled = 0;    ///< queued, not asked for again
    std::uint64_t dropped = 0;      ///< decoded but not asked for again
    std::uint64_t refused = 0;      ///< asks not queued: the stage was at capacity
    std::uint64_t failed = 0;       ///< pages whose decode failed, each counted once
    std::uint64_t heldBytes = 0;    ///< decoded bytes held now (ready, not yet uploaded)
    std::uint64_t peakHeldBytes = 0;
    double decodeSeconds = 0.0; ///< decode threads' time spent decoding
};

/**
 * See the note above. The cache must outlive the stage; the threads are joined (queued pages
 * released) on destruction. Main-thread methods are not thread-safe among themselves.
 */
class GeometryDecodeStage final : public IDecodedGeometry {
public:
    /** `grids`: each prototype's position grid; `pageSize`: the file's (bounds a decode).
     *  Errors: Internal when the system cannot start a decode thread. */
    [[nodiscard]] static Result<std::unique_ptr<GeometryDecodeStage>> create(
            cache::PageCache& cache,
            std::vector<storage::PositionGrid> grids,
            std::uint32_t pageSize,
            const DecodeStageOptions& options = {});
    ~GeometryDecodeStage() override;
    GeometryDecodeStage(const GeometryDecodeStage&) = delete;
    GeometryDecodeStage& operator=(const GeometryDecodeStage&) = delete;

    void beginFrame();
    [[nodiscard]] bool prepare(std::uint64_t page) override;
    [[nodiscard]] const DecodedGeometry* decoded(std::uint64_t page) const override;
    void uploaded(std::uint64_t page) override;

    /** Blocks until no decode is queued or running; the next beginFrame() makes them ready. */
    void drain();
    /** Why pages failed to decode since the last call (each page once, then never asked for
     *  again): "page N: ...". */
    [[nodiscard]] std::vector<Status> takeFailures();
    [[nodiscard]] const DecodeStageStats& stats() const noexcept;


private:
    GeometryDecodeStage(
            cache::PageCache& cache,
            std::vector<storage::PositionGrid> grids,
            std::uint32_t pageSize,
            const DecodeStageOptions& options);

    struct Impl;
    std::unique_ptr<Impl> mImpl;
};

} // namespace ff::runtime
