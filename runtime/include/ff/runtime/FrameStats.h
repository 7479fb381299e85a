#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace ff::runtime {

/** Per-frame statistics: part of the product (JSON for machines), not debug output. */
struct FrameStats {
    std::uint64_t nodesVisited = 0;  ///< node records read by selection
    std::uint64_t nodesCulled = 0;   ///< outside the frustum
    std::uint64_t nodesOccluded = 0; ///< skipped because an occlusion test found them hidden
    /** The triangles below the nodes a test found hidden, at full detail (what their subtrees
     *  hold, instances counted): format 2's records carry the count; format 1's do not, 0. */
    std::uint64_t trianglesOccluded = 0;
    std::uint64_t instancesEntered = 0; ///< instance nodes refined into their prototype
    std::uint64_t cubesDrawn = 0;
    std::uint64_t cubeFacesDrawn = 0; ///< front-facing faces of drawn cubes
    /** Cubes also drawn as occluders (depth only) by the front-to-back walk. */
    std::uint64_t occluderCubes = 0;
    /** Front-facing cube faces drawn per level of their own hierarchy (index = level). */
    std::vector<std::uint64_t> cubeFacesPerLevel;
    std::uint64_t trianglesDrawn = 0;
    /** Cells drawn as their stand-in (a simplified copy of their subtree; its triangles are
     *  among trianglesDrawn). */
    std::uint64_t standInsDrawn = 0;
    /** Cells drawn as their splats (builder/src/Splats.h), and the splats drawn; the splat sets'
     *  triangles are among trianglesDrawn. */
    std::uint64_t splatSetsDrawn = 0;
    std::uint64_t splatsDrawn = 0;
    /** Cells where `--representation` forced a kind they did not keep, drawn as the nearest
     *  kept one instead (their other stand-in, else their cube). */
    std::uint64_t representationFallbacks = 0;
    std::uint64_t geometryDraws = 0; ///< draw commands for geometry (merged page runs)
    std::uint64_t pagesUploaded = 0; ///< geometry pages sent to the GPU this frame
    /** Cells drawn coarser than the ε rule wanted because pages were not resident ("debt"). */
    std::uint64_t nodesDeferred = 0;
    std::uint64_t pagesMissing = 0; ///< page lookups that found no usable page (pending or failed)
    /** Geometry pages the frame's GPU upload budget refused (their cells were drawn as cubes). */
    std::uint64_t uploadsRefused = 0;
    /** Format 2 pages decoded on the render thread: admitted, then evicted from the GPU arena
     *  before their draw within the same frame, or, for a frame that must be complete, not
     *  decoded yet when it was drawn the last time (both: an arena smaller than the frame). */
    std::uint64_t pagesDecodedOnDraw = 0;
    std::uint64_t occlusionQueries = 0; ///< occlusion tests issued (a multiquery counts once)
    std::uint64_t queriesWaited = 0;    ///< answers the walk had to wait for (nothing else to do)
    /** With occlusion culling on: 1 if the frame was drawn without tests, because the last
     *  tested frame hid too little to pay for them (OcclusionOptions::minHiddenShare). */
    std::uint64_t occlusionSkipped = 0;
    double selectMs = 0.0; ///< traversal, not counting the batches the renderer drew meanwhile
    double drawMs = 0.0;   ///< every batch's uploads and submission + GPU until finished (glFinish)
    double occlusionMs = 0.0; ///< issuing occlusion tests and reading (or waiting for) answers
    double totalMs = 0.0;     ///< selectMs + occlusionMs + drawMs

    std::string toJson() const;
};

} // namespace ff::runtime
