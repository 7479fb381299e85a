#pragma once

#include <ff/runtime/Camera.h>
#include <ff/runtime/DrawList.h>
#include <ff/runtime/FrameStats.h>
#include <ff/runtime/Frustum.h>
#include <ff/runtime/PageAccess.h>
#include <ff/runtime/TransformMetric.h>
#include <ff/storage/SceneFile.h>
#include <ff/storage/Status.h>

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <unordered_set>
#include <vector>

namespace ff::runtime {

enum class Method {
    Hierarchical, ///< Chamberlain's traversal: frustum culling, ε rule, cubes back to front
    Full,         ///< every triangle of every instance, no hierarchy (the brute-force baseline)
};

/** How color cubes reach the screen. */
enum class CubeStyle {
    Faces,  ///< the visible faces as quads (Chamberlain et al.)
    Points, ///< one point per cube: visible faces blended by projected area, alpha by coverage
    Auto,   ///< points when ε <= 2 pixels (every drawn cube then covers at most 4 pixels), else faces
};

/** The names users type and read (`--method`, `--cube-draw`, bench scenarios, the HUD): one
 *  table each, in Selection.cpp. */
const char* methodName(Method method) noexcept;
/** "hierarchical" or "full"; nullopt for anything else. */
std::optional<Method> parseMethod(std::string_view name) noexcept;
const char* cubeStyleName(CubeStyle style) noexcept;
/** "faces", "points" or "auto"; nullopt for anything else. */
std::optional<CubeStyle> parseCubeStyle(std::string_view name) noexcept;
/** Every cube style's name, in the table's order (option checks, messages). */
std::vector<std::string> cubeStyleNames();

/**
 * Told of what selection draws, for analysis tools (`farfield stats --paths`) and tests. Optional:
 * with no observer set, selection pays one null check per drawn cube and nothing else.
 * Called on the thread that runs select(), during select().
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
    /** A cube whose coverage (alpha) along the three axes differs by more than this is refused
     *  where the cell can be refined: such a cell (slabs of a venetian blind, a sheet seen
     *  edge-on) looks opaque from one side and transparent from another, and interpolating its
     *  faces tears or leaks at views between the axes. 1 never refuses. */
    float maxCubeAnisotropy = 1.0f;
    /** Multiplies the priority of the pages this selection asks for (prefetch asks below the
     *  frame being drawn). */
    float priorityScale = 1.0f;
    float viewportWidth = 640.0f;
    float viewportHeight = 480.0f;
    /** If set, told of every drawn cube (borrowed; must outlive the select() calls). */
    ISelectionObserver* observer = nullptr;
};

/**
 * Per-frame selection (Chamberlain et al. '96, §3): walks the scene from the instance-level
 * root, skipping cells outside the frustum, drawing a cell as its color cube when its box
 * covers less than ε² pixels, a cell's own triangles when it is refined (each triangle once), and
 * children in back-to-front order. Instances enter their prototype's hierarchy with the
 * instance transform. CPU only: no GL here.
 *
 * Pages come through an IPageAccess and selection never waits for one: a cell whose children
 * or triangles are not Ready is drawn as its own cube instead (counted as debt in the stats)
 * and the missing pages are asked for, larger projected size first. A failed page leaves its
 * subtree drawn with the nearest resident ancestor's cube and is reported once.
 *
 * Main thread only. Scratch memory is reused between frames.
 */
class Selection {
public:
    Selection(const storage::SceneFile& scene, IPageAccess& pages);

    /** Fills `out` (cleared first) and the selection counters of `stats`. Errors only for what
     *  leaves nothing to draw: the root page failed. */
    [[nodiscard]] Status select(const Camera& camera, const SelectionOptions& options, DrawList& out, FrameStats& stats);

    /** Failures first met during the last select() (each is reported once per Selection). */
    const std::vector<Status>& newFailures() const noexcept { return mNewFailures; }

private:
    struct ChildEntry {
        storage::NodeRecord record;
        storage::NodeRef ref;
        float distance;
    };

    enum class Fetch { Ready, Missing };

    void visit(const storage::NodeRecord& node, storage::NodeRef ref, std::uint32_t transform, int depth);
    /** Looks a page up; Failed pages are reported once and read as Missing. */
    Fetch fetch(std::uint64_t page, storage::PageType type, float priority, std::span<const std::byte>& payload);
    Fetch readNode(storage::NodeRef ref, float priority, storage::NodeRecord& out);
    /** Appends the node's own geometry runs to mSegments if every page is Ready. */
    Fetch collectGeometry(const storage::NodeRecord& node, float priority);
    void emitCube(const storage::NodeRecord& node, storage::NodeRef ref, std::uint32_t transform);
    void defer(const storage::NodeRecord& node, storage::NodeRef ref, std::uint32_t transform);
    std::uint32_t pushTransform(const glm::mat4& transform);
    void selectFull();
    void mergeGeometryDraws();
    void collectPrototypeGeometry(std::uint32_t prototype);
    void reportFailure(const Status& failure);

    const storage::SceneFile& mScene;
    IPageAccess& mPages;
    std::unordered_set<std::string> mReported; ///< messages ("page N: ...") already reported
    std::vector<Status> mNewFailures;
    // Per-frame state.
    const Camera* mCamera = nullptr;
    SelectionOptions mOptions;
    DrawList* mOut = nullptr;
    FrameStats* mStats = nullptr;
    float mPixelScale = 1.0f;
    std::vector<TransformMetric> mMetrics; ///< per transform: local sizes to world sizes
    std::vector<Frustum> mFrusta; ///< per transform: the frustum in that local frame
    std::vector<ChildEntry> mChildStack;
    std::vector<storage::GeometrySegment> mSegments;
    /** Full method: every geometry run of each prototype, merged per page (built on demand). */
    std::vector<std::vector<storage::GeometrySegment>> mPrototypeGeometry;
    std::vector<bool> mPrototypeGeometryReady;
};

} // namespace ff::runtime
