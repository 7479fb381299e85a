#include <ff/runtime/FrameRenderer.h>

#include <chrono>

namespace ff::runtime {

FrameRenderer::FrameRenderer(const storage::SceneFile& scene, std::unique_ptr<Renderer> renderer)
    : mSelection(scene)
    , mRenderer(std::move(renderer)) {}

Result<std::unique_ptr<FrameRenderer>> FrameRenderer::create(
        const storage::SceneFile& scene, const RendererOptions& options) {
    FF_ASSIGN_OR_RETURN(std::unique_ptr<Renderer> renderer, Renderer::create(scene, options));
    return std::unique_ptr<FrameRenderer>(new FrameRenderer(scene, std::move(renderer)));
}

Result<Frame> FrameRenderer::render(
        const Camera& camera, SelectionOptions selection, int width, int height, int supersample) {
    using Clock = std::chrono::steady_clock;
    Frame frame;
    // The ε rule counts pixels of the output image: supersampling refines the samples, not
    // the choice of representation.
    selection.viewportWidth = static_cast<float>(width);
    selection.viewportHeight = static_cast<float>(height);
    const auto start = Clock::now();
    FF_RETURN_IF_ERROR(mSelection.select(camera, selection, mDrawList, frame.stats));
    frame.stats.selectMs = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    FF_ASSIGN_OR_RETURN(frame.image, mRenderer->render(mDrawList, camera, width, height, supersample, frame.stats));
    frame.stats.totalMs = frame.stats.selectMs + frame.stats.drawMs;
    return frame;
}

} // namespace ff::runtime
