#pragma once

#include <ff/runtime/Camera.h>
#include <ff/runtime/Selection.h>

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string_view>

namespace ff::runtime {

/** What one frame may spend besides time: the bounds DESIGN.md's runtime rules set. */
struct FrameBudgets {
    /** Finished page reads the streaming cache installs before the frame (PageCache::pump). */
    std::size_t pageInstallsPerFrame = 64;
    /** Geometry pages not yet on the GPU that the frame may upload; a cell whose page is over
     *  the budget is drawn as its cube this frame and counted as debt. 0: no bound. */
    std::uint32_t gpuUploadsPerFrame = 0;
    /** Bytes of draw list (runs, cubes, transforms) handed to the renderer at once: the traversal
     *  flushes a batch when it is full, so a frame's transient memory does not grow with its
     *  cut. A frame that fits draws in one batch, as if there were no bound. */
    std::size_t drawBatchBytes = 16u << 20;
};

/**
 * Occlusion culling (OcclusionTraversal): a front-to-back walk that tests node boxes against
 * what is already drawn before drawing their subtrees, with CHC++'s temporal coherence.
 */
/** How occlusion tests are answered (docs/methods.md §9). */
enum class OcclusionBackend {
    Queries, ///< hardware occlusion queries, answered late (CHC++)
    Hzb,     ///< a max-depth pyramid of the depth read back, tested on the CPU, answered at once
};

/** "queries" / "hzb", and back. */
const char* occlusionBackendName(OcclusionBackend backend) noexcept;
std::optional<OcclusionBackend> parseOcclusionBackend(std::string_view name) noexcept;

struct OcclusionOptions {
    bool enabled = false;
    OcclusionBackend backend = OcclusionBackend::Queries;
    /** CHC++'s temporal coherence. Off: no history, every node is tested before it is drawn,
     *  every frame (what coherence saves is measured against this). */
    bool coherent = true;
    /** Diagnostic: issue every test but take every answer as visible. The frame is drawn in
     *  occlusion culling's order without its culling, so comparing it with a frustum-culled
     *  frame measures the pixels where surfaces tie in depth and draw order decides. */
    bool ignoreAnswers = false;
    /** Occlusion tests a frame may issue; past it, untested nodes are drawn (Unknown). */
    std::uint32_t queryBudget = 8192;
    /** Nodes waiting for a test are issued together once this many are queued (or when the
     *  walk has nothing else to do). */
    std::uint32_t batchNodes = 32;
    /** A node that stayed visible is tested again only every this many frames (each node at its
     *  own phase, so the tests spread over frames); between tests it is drawn without one. */
    std::uint32_t visibleTestInterval = 8;
    /** Nodes hidden at their last test are tested together, up to this many per query (a
     *  multiquery); a group found visible is tested again node by node. */
    std::uint32_t multiqueryNodes = 8;
    /** A node is tested only if about this many triangles lie below it (a prototype's
     *  triangles shared out by level); smaller subtrees are drawn without a test, which costs
     *  less than testing them. */
    std::uint32_t minTestTriangles = 256;
    /** A test rasterises its box: one whose screen rectangle covers more than this many pixels
     *  per triangle it could save is not made (the node is drawn). On llvmpipe a triangle costs
     *  about as much as 20 pixels of a depth-only box (docs/methods.md §9). */
    float testPixelsPerTriangle = 20.0f;
    /** Color cubes met by the front-to-back walk are drawn there too, depth only, as occluders:
     *  a pixel is hidden behind them once the opacity accumulated over it reaches
     *  1 - opacityThreshold (the faces' alpha composited front to back). At 0, only faces of
     *  alpha 1 occlude (exact: nothing shows through them); above 0 (aggregate opacity, after
     *  Zhang et al.'s hierarchical occlusion maps) translucent cubes occlude together what at
     *  most that share of light would show through: approximate. */
    bool cubesOcclude = true;
    float opacityThreshold = 0.0f;
    /** Where culling does not pay, frames go without it: after a frame whose tests hid less
     *  than this share of the work (the triangles and cubes their subtrees would have drawn,
     *  estimated, against those drawn), the next frames are drawn with frustum culling alone,
     *  no tests and no second pass, until a few have passed or the camera jumps; then a frame
     *  tests again (docs/methods.md §9; 0.05 is the share measured there). 0, the default:
     *  every frame is tested (measured no faster where it skips; methods §9). */
    float minHiddenShare = 0.0f;
};

/**
 * Everything one frame is drawn from: the camera, the output viewport, the representation
 * choices, the time and the budgets. The one argument of traversal, drawing and statistics.
 */
struct FrameContext {
    Camera camera;
    /** The output image or window in pixels; the ε rule counts these pixels. */
    int width = 640;
    int height = 480;
    /** Samples per pixel along each axis (a reference): refines the samples, not the choice of
     *  representation. */
    int supersample = 1;
    /** Animation time in seconds, where animated bounds and keyframes are evaluated. Nothing
     *  is animated yet: it is carried so the seam exists when keyframed splats land. */
    double timeSeconds = 0.0;
    SelectionOptions selection;
    OcclusionOptions occlusion;
    FrameBudgets budgets;
};

} // namespace ff::runtime
