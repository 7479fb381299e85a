#pragma once

namespace ff::builder {

/** How the builder subdivides and bakes. The defaults are the ones the benchmarks chose. */
struct HierarchyParams {
    /** Triangles a drawn color cube costs (three visible quads = six triangles). Chamberlain §4:
     *  a cell stops subdividing when its triangles cost no more than its children's cubes. */
    float cubeCost = 6.0f;
    /** A triangle whose bounding-box edge exceeds tolerance x the cell edge stays at that cell
     *  instead of descending (Wand & Strasser §3.1); it is drawn once, with that cell. */
    float largeTriangleTolerance = 1.0f;
    /** Deepest octree level (root = 0). Cells there are leaves whatever they hold. */
    int maxDepth = 20;
    /** Samples per face edge when baking color cubes (>= 4 recommended). */
    int bakeResolution = 8;
    /** Bake inner nodes directly from all their triangles instead of compositing children
     *  (Chamberlain §4's alternative). Slower; applies within memory-sized chunks, above them
     *  the builder composites. */
    bool bakeInnerDirect = false;
};

} // namespace ff::builder
