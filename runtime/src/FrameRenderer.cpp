#include <ff/runtime/FrameRenderer.h>

#include <chrono>

namespace ff::runtime {

namespace {

// Ends the page access's frame on every path out, so a failed frame still cancels the requests
// it no longer wants.
class FrameBracket {
public:
    explicit FrameBracket(IPageAccess& pages) : mPages(pages) { mPages.beginFrame(); }
    ~FrameBracket() { mPages.endFrame(); }
    FrameBracket(const FrameBracket&) = delete;
    FrameBracket& operator=(const FrameBracket&) = delete;

private:
    IPageAccess& mPages;
};

} // namespace

FrameRenderer::FrameRenderer(
        const storage::SceneFile& scene, std::unique_ptr<IPageAccess> ownedPages, IPageAccess& pages)
    : mOwnedPages(std::move(ownedPages))
    , mPages(pages)
    , mSelection(scene, pages)
    , mPrefetchSelection(scene, pages) {}

void FrameRenderer::prefetch(SelectionOptions selection) {
    if (!mPrefetchCamera)
        return;
    selection.priorityScale *= 0.25f;
    FrameStats ignored;
    // Its only effect is the page requests its lookups make; what it would draw is dropped.
    (void)mPrefetchSelection.select(*mPrefetchCamera, selection, mPrefetchList, ignored);
}

Result<std::unique_ptr<FrameRenderer>> FrameRenderer::create(
        const storage::SceneFile& scene, const RendererOptions& options) {
    auto pages = std::make_unique<MappedPageAccess>(scene);
    IPageAccess& access = *pages;
    std::unique_ptr<FrameRenderer> frameRenderer(new FrameRenderer(scene, std::move(pages), access));
    FF_ASSIGN_OR_RETURN(frameRenderer->mRenderer, Renderer::create(scene, access, options));
    return frameRenderer;
}

Result<std::unique_ptr<FrameRenderer>> FrameRenderer::create(
        const storage::SceneFile& scene, IPageAccess& pages, const RendererOptions& options) {
    std::unique_ptr<FrameRenderer> frameRenderer(new FrameRenderer(scene, nullptr, pages));
    FF_ASSIGN_OR_RETURN(frameRenderer->mRenderer, Renderer::create(scene, pages, options));
    return frameRenderer;
}

// Both ways of drawing a frame: selection (timed), the drawing `draw` does, then prefetch for
// the camera ahead, all inside one page-access frame.
template <typename Draw>
Status FrameRenderer::frame(const Camera& camera, SelectionOptions selection, int width, int height, FrameStats& stats,
                            Draw&& draw) {
    // The ε rule counts pixels of the output image: supersampling refines the samples, not
    // the choice of representation.
    selection.viewportWidth = static_cast<float>(width);
    selection.viewportHeight = static_cast<float>(height);
    const auto start = std::chrono::steady_clock::now();
    const FrameBracket bracket(mPages);
    FF_RETURN_IF_ERROR(mSelection.select(camera, selection, mDrawList, stats));
    stats.selectMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    FF_RETURN_IF_ERROR(draw());
    prefetch(selection);
    stats.totalMs = stats.selectMs + stats.drawMs;
    return Status::ok();
}

Result<Frame> FrameRenderer::render(
        const Camera& camera, SelectionOptions selection, int width, int height, int supersample) {
    Frame result;
    FF_RETURN_IF_ERROR(frame(camera, selection, width, height, result.stats, [&]() -> Status {
        FF_ASSIGN_OR_RETURN(result.image, mRenderer->render(mDrawList, camera, width, height, supersample, result.stats));
        return Status::ok();
    }));
    return result;
}

Result<FrameStats> FrameRenderer::present(const Camera& camera, SelectionOptions selection, int width, int height) {
    FrameStats stats;
    FF_RETURN_IF_ERROR(frame(camera, selection, width, height, stats, [&] {
        return mRenderer->present(mDrawList, camera, width, height, stats);
    }));
    return stats;
}

} // namespace ff::runtime
