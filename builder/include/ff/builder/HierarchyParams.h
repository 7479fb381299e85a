#pragma once

#include <cstdint>
#include <optional>
#include <string_view>

namespace ff::builder {

/** How a hierarchy splits its triangles (Meißner, Bartz et al. 1999, §3; docs/methods.md §10). */
enum class Decomposition {
    Octree,   ///< adaptive octree with Chamberlain's cost rule (the default)
    Dbvd,     ///< dimension-oriented bounding volumes: the largest side cut into cube-like slabs
    Phbvo,    ///< binned-SAH bounding volume hierarchy over triangle barycentres, 2- or 4-ary
    Balanced, ///< SGI-opoptimize-like: up to eight children at the load-balancing median planes
    Orsd,     ///< octree over a voxel grid's relevant-cell load (isosurfaces only)
};

/** "octree", "dbvd", "phbvo", "balanced", "orsd". */
std::string_view decompositionName(Decomposition decomposition) noexcept;
std::optional<Decomposition> parseDecomposition(std::string_view name) noexcept;

/** The parameters of the non-octree decompositions; each names the paper's parameter it is. */
struct DecompositionParams {
    /** D-BVD: an entity with this many triangles or fewer is a leaf (the paper's "minimal
     *  number of polygons"). */
    unsigned minTriangles = 512;
    /** D-BVD: an entity whose largest side is this short or shorter is a leaf (0 = no limit). */
    float minSize = 0.0f;
    /** D-BVD: how far a split plane may move to cut fewer triangles, as a share of a slab. */
    float planeShift = 0.25f;
    /** p-HBVO's Max_Triangles_Per_Entity and balanced's tri_max: larger entities split. */
    unsigned maxTriangles = 512;
    /** balanced's tri_min: no child gets fewer (it splits fewer ways instead). */
    unsigned balancedMinTriangles = 64;
    /** p-HBVO: children per inner node, 2 (the paper's binary tree) or 4 (its collapsed
     *  quad tree, +20 % fps in the paper). */
    unsigned arity = 4;
    /** ORSD: a block whose relevant-cell load exceeds this splits into its eight octants. */
    unsigned relevantCells = 256;
    /** Max_Decomposition_Depth of every decomposition (levels below the root it starts at). */
    int maxDepth = 40;
};

/** Format 2's leaves: subtrees of at most this many triangles become one leaf of clusters. */
inline constexpr std::uint64_t kClusterLeafTriangles = 4096;
/** The same with cluster nodes, whose slab trees replace the decomposition below a leaf: an
 *  octree's cells of a few thousand triangles on a heightfield include slivers where the surface
 *  crosses a cell's middle height, tens of units wide and two triangles deep, that cover a
 *  pixel from far and are drawn whole, each pulling in a page. From leaves this large the slabs
 *  cut the surface instead (docs/results, "Cluster nodes from larger leaves": the 10^9 terrain
 *  filling the screen from above 50.2 MB instead of 85.4). */
inline constexpr std::uint64_t kClusterNodesLeafTriangles = 65536;
/** A prototype placed once with more triangles than this gets cluster nodes unless told
 *  otherwise. At format 2's ~7 bytes a triangle, a prototype this size or smaller costs at most
 *  ~60 MB drawn whole, within issue 16's 64 MB budget for a complete frame, so its leaves may
 *  be drawn whole and it keeps the fewer bytes (the scanned models' 7.2-7.6 a triangle against
 *  8.1-8.6 with cluster nodes) and the accuracy of triangles (the 4 M terrain from 6 radii: 48.6
 *  dB against 32.3); a larger one would draw whole leaves wherever they cover a pixel or two
 *  (the 64 M terrain's whole view: all 410 MB of it against 21.8 MB; docs/results, "Cluster
 *  nodes by size"). */
inline constexpr std::uint64_t kClusterNodesAboveTriangles = std::uint64_t{1} << 23;
/** The leaf the default gives a prototype placed more than once: about the octree's own leaves
 *  (its cube-cost rule leaves ~12 triangles), so the cut of an instanced tree stops where
 *  format 1's does (docs/results, "Format 2 paged"). */
inline constexpr std::uint64_t kInstancedLeafTriangles = 16;

/** How a format 2 prototype's leaves are shaped (HierarchyParams::leavesFor). */
struct PrototypeLeaves {
    std::uint64_t leafTriangles = kClusterLeafTriangles; ///< subtrees this small become one leaf
    bool clusterNodes = false;                           ///< each leaf split into cluster nodes
};

/** How the builder subdivides and bakes. The defaults are the ones the benchmarks chose. */
struct HierarchyParams {
    Decomposition decomposition = Decomposition::Octree;
    DecompositionParams split;
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
     *  the builder composites. The bounding-volume decompositions composite their children's
     *  boxes seen through their cubes (their children are not octants: no quadrants). */
    bool bakeInnerDirect = false;
    /** Format 2 only: a subtree of at most this many triangles is written as one leaf of whole
     *  clusters, so a node's 48-byte record is spread over many triangles (the v2 estimate of
     *  docs/results "Compact geometry" was measured at 4096). 0 keeps the hierarchy's leaves.
     *  Unset: kClusterLeafTriangles, or kClusterNodesLeafTriangles with cluster nodes, for a
     *  prototype placed once; kInstancedLeafTriangles for one placed more (leavesFor()). */
    std::optional<std::uint64_t> clusterLeafTriangles;
    /** Format 2 only: each leaf gets a tree of nodes, at most four wide, down to pieces of
     *  about a cluster, each with its bounds and cube, so a cut can stop inside a leaf
     *  (builder/src/ClusterNodes.h): far views draw far fewer triangles for 0.6-1 byte a
     *  triangle more (docs/results "Cluster nodes"). Unset: by the prototype's size, for a
     *  prototype placed once with more than clusterNodesAboveTriangles (leavesFor()). */
    std::optional<bool> clusterNodes;
    /** Where clusterNodes is unset: the size above which a prototype placed once gets them. */
    std::uint64_t clusterNodesAboveTriangles = kClusterNodesAboveTriangles;

    /** Format 2 only: cells carry simplified stand-ins of their subtrees, drawn where their
     *  error projects below ε pixels (builder/src/StandIns.h, docs/methods.md §12). */
    bool standIns = false;
    /** Format 2 only: cells carry point splats standing in for their subtrees, spaced at
     *  1/splatSpacing of the largest side of the cell's bounds (8-16; 0: none), where no
     *  simplified stand-in pays (builder/src/Splats.h, docs/methods.md §13). */
    int splatSpacing = 0;
    /** Format 2 only: a cell's candidate stand-ins are drawn from its six face directions beside
     *  the geometry they stand for, their errors raised where the images differ, and the one
     *  that pays best kept (builder/src/StandInChoice.h, docs/methods.md §14); false: by rule (a
     *  simplified copy where one reduces, else splats, at their geometric errors). */
    bool measureStandIns = true;
    /** Whether cells get stand-ins of either kind. */
    [[nodiscard]] bool anyStandIns() const noexcept { return standIns || splatSpacing > 0; }
    /**
     * How the leaves of a prototype of `triangles` triangles placed `placements` times are
     * shaped: cluster nodes where clusterNodes says, else by size (kClusterNodesAboveTriangles,
     * placed once only); leaves of clusterLeafTriangles where set, else, placed more than once,
     * kInstancedLeafTriangles, and placed once, the default for its cluster nodes. Where a
     * leaf's cell covers more than ε pixels all its triangles are drawn, in every placement in
     * view, while its records are stored once for all of them: at the forest's view a tree
     * placed 16,384 times with leaves of 4,096 triangles drew 42 times format 1's triangles,
     * and 16 trees with leaves of 256 (the default shared among the placements, tried) still
     * 16 times (docs/results, "Format 2 paged"). A prototype placed once (a terrain, a scan)
     * keeps the large leaves that hold it to 8 bytes a triangle.
     */
    [[nodiscard]] PrototypeLeaves leavesFor(std::uint64_t placements, std::uint64_t triangles) const noexcept {
        const bool splitLeaves = clusterNodes.value_or(placements <= 1 && triangles > clusterNodesAboveTriangles);
        if (clusterLeafTriangles)
            return {*clusterLeafTriangles, splitLeaves};
        if (placements > 1)
            return {kInstancedLeafTriangles, splitLeaves};
        return {splitLeaves ? kClusterNodesLeafTriangles : kClusterLeafTriangles, splitLeaves};
    }
};

} // namespace ff::builder
