#pragma once

#include <ff/runtime/Camera.h>
#include <ff/runtime/DecodedGeometry.h>
#include <ff/runtime/DrawList.h>
#include <ff/runtime/FrameStats.h>
#include <ff/runtime/Image.h>
#include <ff/runtime/FrameContext.h>
#include <ff/runtime/Traversal.h>
#include <ff/storage/SceneIndex.h>
#include <ff/storage/Status.h>

#include <glm/glm.hpp>

#include <cstdint>
#include <memory>
#include <vector>

namespace ff::runtime {

struct RendererOptions {
    /** Bytes of GPU memory for geometry pages; a frame that needs more is drawn in batches. */
    std::uint64_t gpuBudgetBytes = 512ull << 20;
    /** Background, linear RGB. */
    glm::vec3 backgroundLinear{0.70f, 0.75f, 0.83f};
};

/** What of one batch shows in a finished frame (Renderer::visibleParts, the oracle's answer). */
struct BatchVisibility {
    /** A flag per triangle: the batch's geometry draws' triangles, one draw after another. */
    std::vector<bool> triangles;
    std::vector<bool> cubes; ///< a flag per cube of the batch
};

/** Where a frame goes. */
enum class FrameOutput {
    Image,  ///< the renderer's own target, read back and resolved (coverage kept as alpha)
    Window, ///< the default framebuffer (a window's back buffer), no readback
};

/**
 * Draws a frame's DrawList batches with OpenGL 4.5 core: each batch's opaque geometry first
 * (pages uploaded once into a GPU page arena, drawn with one multi-draw per arena batch, instance
 * transforms from a storage buffer), then its color cubes blended front-over-back in the list's
 * back-to-front order, premultiplied, in linear space (sRGB framebuffer). The same code runs
 * under OSMesa and in a GLFW window.
 *
 * A frame is beginFrame(), draw() once per batch (the traversal's IDrawSink), then
 * finishImage() or finishPresent(). It is also the traversal's IUploadGate (at most
 * FrameBudgets::gpuUploadsPerFrame pages not yet in the arena are admitted per frame; a format 2
 * page only once it is decoded, IDecodedGeometry) and its
 * IOcclusionTester (hardware occlusion queries against the frame's depth so far).
 *
 * Needs a current GL 4.5 context; main thread only.
 */
class Renderer final : public IDrawSink, public IUploadGate, public IOcclusionTester {
public:
    /** `decodedGeometry`: where a format 2 scene's pages come decoded from (required for one,
     *  borrowed: it must outlive the renderer). Errors: InvalidArgument without it, Internal
     *  (GL). */
    [[nodiscard]] static Result<std::unique_ptr<Renderer>> create(
            const storage::SceneIndex& scene,
            const RendererOptions& options = {},
            IDecodedGeometry* decodedGeometry = nullptr);
    ~Renderer() override;
    Renderer(const Renderer&) = delete;
    Renderer& operator=(const Renderer&) = delete;

    /**
     * Starts a frame of frame.width x frame.height (x frame.supersample for an Image): sizes and
     * clears the target (transparent for an Image, whose background is composited after the
     * resolve; the opaque background for a Window) and resets the upload budget. Adds its time
     * to stats.drawMs. Errors: InvalidArgument (size), Internal (GL).
     */
    [[nodiscard]] Status beginFrame(const FrameContext& frame, FrameOutput output, FrameStats& stats);

    /** Draws one batch. Adds pagesUploaded and drawMs to `stats`. */
    [[nodiscard]] Status draw(const DrawList& batch, FrameStats& stats) override;

    /** Admits a geometry page for this frame (see the class comment). */
    [[nodiscard]] bool admit(std::uint64_t geometryPage) override;
    /** Format 2: admit pages the decode stage has not decoded yet and decode them on this
     *  thread as they are drawn (FrameStats::pagesDecodedOnDraw). For a frame that must be
     *  complete and cannot be otherwise: one whose pages do not all fit the GPU arena, so each
     *  try evicts pages the next needs decoded again. Off by default. */
    void setDecodeOnDraw(bool on) noexcept;

    // IOcclusionTester, by FrameContext::occlusion.backend: GL_ANY_SAMPLES_PASSED_CONSERVATIVE
    // queries, pooled, submit() flushes; or (hzb) a depth pyramid of the depth read back when
    // geometry was drawn since the last read, answered at once.
    [[nodiscard]] QueryTicket issue(std::span<const OcclusionBox> group) override;
    void submit() override;
    [[nodiscard]] bool ready(QueryTicket ticket) override;
    [[nodiscard]] bool anyVisible(QueryTicket ticket) override;

    /** Waits for the GPU (counted in drawMs), reads the target back and resolves it to
     *  width x height. Errors: Internal (GL error). */
    [[nodiscard]] Result<Image> finishImage(FrameStats& stats);

    /**
     * Copies the frame byte for byte to (0, 0, width, height) of framebuffer 0: the window shows
     * the same sRGB bytes as an Image of the frame (up to rounding of the background under
     * blended cubes). Leaves framebuffer 0 bound, GL_FRAMEBUFFER_SRGB and blending off. Does not
     * wait for the GPU (drawMs counts submission only).
     */
    [[nodiscard]] Status finishPresent(FrameStats& stats);

    /**
     * The oracle's question, asked after a frame's every batch was drawn: which of `batch`'s
     * triangles and cubes show at least one sample of the finished frame. The batch is drawn
     * again, nothing written but a bit per primitive whose fragment passes the depth test:
     * at == for triangles (the same shader and inputs give the same depths; surfaces tied in
     * depth both count), at < for cubes (they write no depth: one shows wherever it lies in
     * front of the opaque surface, and a face of alpha 0 does not count). A triangle whose page
     * is no longer on the GPU counts as visible.
     */
    [[nodiscard]] BatchVisibility visibleParts(const DrawList& batch);

    /** Bytes of the GPU page arena holding geometry pages now (at most the GPU budget). */
    [[nodiscard]] std::uint64_t residentBytes() const noexcept;

private:
    struct Impl;
    explicit Renderer(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> mImpl;
};

} // namespace ff::runtime
