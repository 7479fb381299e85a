#pragma once

// What a user chooses about how a frame is drawn (--method, --epsilon, --cube-draw, ...): the
// options every traversal reads, and the one table of their names.

#include <ff/storage/SceneFormat.h>

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace ff::runtime {

enum class Method {
    Hierarchical, ///< Chamberlain's traversal: frustum culling, ε rule, cubes back to front
    Full,         ///< every triangle of every instance, no hierarchy (the brute-force baseline)
};

/** How color cubes reach the screen. */
enum class CubeStyle {
    Faces,  ///< the visible faces as quads (Chamberlain et al.)
    /** One GL point per cube, its visible faces' colours weighted by their projected area and
     *  alpha by coverage: a cube drawn small, not a splat (no footprint, no filtering). */
    AreaWeightedPoints,
    Auto,   ///< points when ε <= 2 pixels (every drawn cube then covers at most 4 pixels), else faces
};

/** What a cell that the ε rule would refine may be drawn as instead (`--representation`). */
enum class Representation {
    /** Its cube where the cell is below ε pixels, else its stand-in (a simplified copy of the
     *  subtree or splats, format 2 files built with --stand-ins or --splats) where the
     *  stand-in's error is below ε pixels, else its own payload and children. */
    Auto,
    Cube,       ///< never a stand-in (the hierarchy as before stand-ins)
    /** A simplified stand-in wherever auto would draw the cube or a stand-in; a cell without
     *  one is refined (its own triangles and children). */
    Simplified,
    /** Splats wherever auto would draw the cube or a stand-in; a cell without them is refined. */
    Splats,
};

/** How splats are drawn (`--splat-size`, `--splat-shape`): opaque, depth-tested points; a
 *  cell's splats are drawn only where a diameter of `pixels` covers twice their error on
 *  screen (no holes), and at that twice (at least a pixel). */
struct SplatStyle {
    float pixels = 2.0f; ///< the largest diameter on screen
    bool round = true;   ///< discs; false: squares
};

/** The names users type and read (`--method`, `--cube-draw`, bench scenarios, the HUD): one
 *  table each, in Selection.cpp. */
const char* methodName(Method method) noexcept;
/** "hierarchical" or "full"; nullopt for anything else. */
std::optional<Method> parseMethod(std::string_view name) noexcept;
const char* representationName(Representation representation) noexcept;
/** "auto", "cube", "simplified" or "splats"; nullopt for anything else. */
std::optional<Representation> parseRepresentation(std::string_view name) noexcept;
const char* cubeStyleName(CubeStyle style) noexcept;
/** "faces", "points" or "auto"; nullopt for anything else. */
std::optional<CubeStyle> parseCubeStyle(std::string_view name) noexcept;
/** Every cube style's name, in the table's order (option checks, messages). */
std::vector<std::string> cubeStyleNames();

/**
 * Told of what selection draws, for analysis tools (`farfield stats --paths`) and tests. Optional:
 * with no observer set, selection pays one null check per drawn cube and nothing else.
 * Called on the thread that runs the traversal, during ITraversal::traverse().
 */
class ISelectionObserver {
public:
    virtual ~ISelectionObserver() = default;
    /** `node` (stored at `ref`) is drawn as its color cube this frame. A prototype node drawn
     *  under several instances is reported once per instance. */
    virtual void cubeDrawn(storage::NodeRef ref, const storage::NodeRecord& node) = 0;
};

struct SelectionOptions {
    Method method = Method::Hierarchical;
    /** A cell whose box covers less than this squared in pixels on screen (its silhouette,
     *  measured at the cell's nearest point) is drawn as its color cube; 0 draws geometry
     *  everywhere. */
    float epsilonPixels = 1.0f;
    CubeStyle cubeStyle = CubeStyle::Auto;
    Representation representation = Representation::Auto;
    SplatStyle splats;
    /** A cube whose coverage (alpha) along the three axes differs by more than this is refused
     *  where the cell can be refined: such a cell (slabs of a venetian blind, a sheet seen
     *  edge-on) looks opaque from one side and transparent from another, and interpolating its
     *  faces tears or leaks at views between the axes. 1 never refuses. */
    float maxCubeAnisotropy = 1.0f;
    /** Multiplies the priority of the pages this selection asks for (prefetch asks below the
     *  frame being drawn). */
    float priorityScale = 1.0f;
    /** If set, told of every drawn cube (borrowed; must outlive the traversals that use it). */
    ISelectionObserver* observer = nullptr;
};

} // namespace ff::runtime
