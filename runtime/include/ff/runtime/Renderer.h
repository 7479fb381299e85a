#pragma once

#include <ff/runtime/Camera.h>
#include <ff/runtime/DrawList.h>
#include <ff/runtime/FrameStats.h>
#include <ff/runtime/Image.h>
#include <ff/runtime/PageAccess.h>
#include <ff/storage/SceneFile.h>
#include <ff/storage/Status.h>

#include <glm/glm.hpp>

#include <cstdint>
#include <memory>

namespace ff::runtime {

struct RendererOptions {
    /** Bytes of GPU memory for geometry pages; a frame that needs more is drawn in batches. */
    std::uint64_t gpuBudgetBytes = 512ull << 20;
    /** Background, linear RGB. */
    glm::vec3 backgroundLinear{0.70f, 0.75f, 0.83f};
};

/**
 * Draws a DrawList with OpenGL 4.5 core: opaque geometry first (pages uploaded once into a GPU
 * page arena, drawn with one multi-draw per batch, instance transforms from a storage buffer),
 * then color cubes blended front-over-back in the list's back-to-front order, premultiplied, in
 * linear space (sRGB framebuffer). The same code runs under OSMesa and in a GLFW window.
 *
 * Needs a current GL 4.5 context; main thread only.
 */
class Renderer {
public:
    /** Geometry pages are read through `pages`, which must outlive the renderer. */
    [[nodiscard]] static Result<std::unique_ptr<Renderer>> create(
            const storage::SceneFile& scene, IPageAccess& pages, const RendererOptions& options = {});
    ~Renderer();
    Renderer(const Renderer&) = delete;
    Renderer& operator=(const Renderer&) = delete;

    /**
     * Renders at (width x supersample) x (height x supersample) and resolves to width x height.
     * Adds pagesUploaded and drawMs to `stats`. Errors: Corrupt (a geometry page failed its
     * checks), InvalidArgument (size), Internal (GL error).
     */
    [[nodiscard]] Result<Image> render(
            const DrawList& list, const Camera& camera, int width, int height, int supersample, FrameStats& stats);

    /**
     * Draws the same frame as render(list, camera, width, height, 1, ...) into the default
     * framebuffer (a window's back buffer) with no CPU readback: rendered over the opaque
     * background in the renderer's own target, then blitted to (0, 0, width, height) of
     * framebuffer 0. The window shows the same sRGB bytes as render()'s image (up to rounding of
     * the background under blended cubes). Leaves framebuffer 0 bound, GL_FRAMEBUFFER_SRGB and
     * blending off. Does not wait for the GPU (drawMs counts submission only). Errors as render().
     */
    [[nodiscard]] Status present(const DrawList& list, const Camera& camera, int width, int height, FrameStats& stats);

    /** Bytes of the GPU page arena holding geometry pages now (at most the GPU budget). */
    [[nodiscard]] std::uint64_t residentBytes() const noexcept;

private:
    struct Impl;
    explicit Renderer(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> mImpl;
};

} // namespace ff::runtime
