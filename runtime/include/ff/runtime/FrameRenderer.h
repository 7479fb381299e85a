#pragma once

#include <ff/runtime/Camera.h>
#include <ff/runtime/FrameStats.h>
#include <ff/runtime/Image.h>
#include <ff/runtime/Renderer.h>
#include <ff/runtime/Selection.h>
#include <ff/storage/SceneFile.h>
#include <ff/storage/Status.h>

#include <cstdint>
#include <memory>
#include <optional>

namespace ff::runtime {

/** A rendered frame with its statistics. */
struct Frame {
    Image image;
    FrameStats stats;
};

/**
 * One scene, one view at a time: selection (CPU) then drawing (GL) into an image, timed.
 * Owns the Selection and Renderer for a scene; needs a current GL 4.5 context. Main thread only.
 */
class FrameRenderer {
public:
    /** Every page resident through the memory map (synchronous: frames are always complete). */
    [[nodiscard]] static Result<std::unique_ptr<FrameRenderer>> create(
            const storage::SceneFile& scene, const RendererOptions& options = {});
    /** Pages through `pages` (e.g. a streaming cache), which must outlive the renderer. */
    [[nodiscard]] static Result<std::unique_ptr<FrameRenderer>> create(
            const storage::SceneFile& scene, IPageAccess& pages, const RendererOptions& options = {});

    /** Renders width x height, supersampled `supersample` x `supersample` (1 = none). */
    [[nodiscard]] Result<Frame> render(
            const Camera& camera, SelectionOptions selection, int width, int height, int supersample = 1);

    /** Selects and draws width x height into the default framebuffer (Renderer::present): a
     *  window's back buffer, no readback. Returns the frame's statistics. */
    [[nodiscard]] Result<FrameStats> present(const Camera& camera, SelectionOptions selection, int width, int height);

    /** Bytes of geometry pages resident in GPU memory (Renderer::residentBytes). */
    [[nodiscard]] std::uint64_t gpuResidentBytes() const noexcept { return mRenderer->residentBytes(); }


    /**
     * Prefetch along the camera's motion: after each following frame, selection also runs for
     * `camera` (where the camera will be a few frames on) only to ask for its pages, at a quarter
     * of the frame's priority. nullopt stops it. Useful with a streaming IPageAccess only.
     */
    void setPrefetchCamera(std::optional<Camera> camera) { mPrefetchCamera = camera; }
    /** Page failures first met by the last frame (each reported once). */
    const std::vector<Status>& newFailures() const noexcept { return mSelection.newFailures(); }

private:
    FrameRenderer(const storage::SceneFile& scene, std::unique_ptr<IPageAccess> ownedPages, IPageAccess& pages);

    std::unique_ptr<IPageAccess> mOwnedPages;
    IPageAccess& mPages;
    Selection mSelection;
    Selection mPrefetchSelection; ///< its own failures and scratch: the frame's stay intact
    std::optional<Camera> mPrefetchCamera;
    DrawList mPrefetchList;
    void prefetch(SelectionOptions selection);
    template <typename Draw>
    Status frame(const Camera& camera, SelectionOptions selection, int width, int height, FrameStats& stats, Draw&& draw);
    std::unique_ptr<Renderer> mRenderer;
    DrawList mDrawList;
};

} // namespace ff::runtime
