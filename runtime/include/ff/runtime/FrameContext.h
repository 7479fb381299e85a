#pragma once

#include <ff/runtime/Camera.h>
#include <ff/runtime/Selection.h>

#include <cstddef>
#include <cstdint>

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
    FrameBudgets budgets;
};

} // namespace ff::runtime
