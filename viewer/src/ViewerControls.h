#pragma once

#include <ff/runtime/Selection.h>

#include <cstdint>

namespace ff::viewer {

/** What the `view` window's keys change live; the frame loop reads it every frame. */
struct ViewerControls {
    float epsilonPixels = 1.0f;
    runtime::Method method = runtime::Method::Hierarchical;
    /** GPU page arena (RendererOptions::gpuBudgetBytes); a change recreates the renderer. */
    std::uint64_t gpuBudgetBytes = 512ull << 20;
    /** Page cache budget once a streaming cache drives the window; 0 = no cache (pages are
     *  read through the memory map), and then `-`/`=` change the GPU budget instead. */
    std::uint64_t cacheBudgetBytes = 0;
    bool hudVisible = true;

    static constexpr float kMinEpsilon = 1.0f / 64.0f; ///< `[` below this goes to 0
    static constexpr std::uint64_t kMinBudgetBytes = 1ull << 20;
    static constexpr std::uint64_t kMaxBudgetBytes = 64ull << 30;

    /** `[`: halves ε; below kMinEpsilon it becomes 0 (all geometry). */
    void halveEpsilon() {
        epsilonPixels = epsilonPixels * 0.5f < kMinEpsilon ? 0.0f : epsilonPixels * 0.5f;
    }
    /** `]`: doubles ε; from 0 it starts again at kMinEpsilon. */
    void doubleEpsilon() {
        epsilonPixels = epsilonPixels > 0.0f ? epsilonPixels * 2.0f : kMinEpsilon;
    }
    void toggleMethod() {
        method = method == runtime::Method::Hierarchical ? runtime::Method::Full
                                                         : runtime::Method::Hierarchical;
    }
    /** `-` / `=`: the budget that governs residency (the cache's if there is one). */
    std::uint64_t& adjustableBudget() {
        return cacheBudgetBytes ? cacheBudgetBytes : gpuBudgetBytes;
    }
    void halveBudget() {
        std::uint64_t& b = adjustableBudget();
        b = b / 2 < kMinBudgetBytes ? kMinBudgetBytes : b / 2;
    }
    void doubleBudget() {
        std::uint64_t& b = adjustableBudget();
        b = b * 2 > kMaxBudgetBytes ? kMaxBudgetBytes : b * 2;
    }
};

/**
 * What the HUD shows for one frame. The frame loop fills what it knows; a streaming cache
 * fills residentBytes/requestsInFlight/debt from its own statistics once it exists.
 */
struct HudInfo {
    const char* navigation = "orbit"; ///< "orbit" or "fly"
    double frameMs = 0.0;             ///< wall time per frame, smoothed
    double selectMs = 0.0;            ///< CPU selection of the last frame
    double drawMs = 0.0;              ///< GL submission of the last frame
    float epsilonPixels = 1.0f;
    runtime::Method method = runtime::Method::Hierarchical;
    std::uint64_t trianglesDrawn = 0;
    std::uint64_t cubesDrawn = 0;
    std::uint64_t debt = 0;             ///< nodes deferred (drawn coarser: pages not resident)
    bool occlusion = false;             ///< --occlusion on: the line below is shown
    double occlusionMs = 0.0;           ///< occlusion tests of the last frame
    std::uint64_t occlusionQueries = 0;
    std::uint64_t queriesWaited = 0;
    bool occlusionSkipped = false; ///< drawn without tests (OcclusionOptions::minHiddenShare)
    std::uint64_t nodesOccluded = 0;
    std::uint64_t trianglesOccluded = 0; ///< below them (format 2; 0 for format 1)
    double renderRatePercent = 0.0; ///< triangles drawn, % of the scene's
    std::uint64_t residentBytes = 0;    ///< GPU page arena now (later: the cache's resident bytes)
    std::uint64_t budgetBytes = 0;      ///< the budget `-`/`=` change
    const char* budgetName = "gpu";     ///< "gpu" or "cache"
    std::uint64_t requestsInFlight = 0; ///< page reads under way (0 without a streaming cache)
    int width = 0;
    int height = 0;
};

} // namespace ff::viewer
