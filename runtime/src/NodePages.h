#pragma once

// What every traversal needs to read the hierarchy and decide a node's representation: page
// lookups that never wait and report each failure once, and Chamberlain's ε rule. Shared by the
// back-to-front and the occlusion traversals, so both draw exactly the same cut.

#include <ff/runtime/Camera.h>
#include <ff/runtime/DrawList.h>
#include <ff/runtime/FrameStats.h>
#include <ff/runtime/Frustum.h>
#include <ff/runtime/PageAccess.h>
#include <ff/runtime/Selection.h>
#include <ff/runtime/TransformMetric.h>
#include <ff/runtime/Traversal.h>
#include <ff/storage/NodeCellV2.h>
#include <ff/storage/NodeRecordV2.h>
#include <ff/storage/SceneIndex.h>

#include <glm/glm.hpp>

#include <algorithm>
#include <array>
#include <span>
#include <string>
#include <unordered_set>
#include <vector>

namespace ff::runtime::detail {

/** Priority for pages nobody can see the size of yet (the root, a full draw). */
inline constexpr float kTopPriority = 1e30f;
/** Deeper than any builder writes (octree levels <= 20 per prototype, instance level <= 24 plus
 *  groups): a file nesting further has a reference cycle, which must not overflow the stack. */
inline constexpr int kMaxNesting = 128;

inline glm::vec3 toVec3(const std::array<float, 3>& a) {
    return {a[0], a[1], a[2]};
}

inline bool isCell(const storage::NodeRecord& node) {
    return node.kind == static_cast<std::uint8_t>(storage::NodeKind::Cell);
}

glm::mat4 instanceTransform(const storage::InstanceRecord& instance);

/** The ε rule's measure: the side, in pixels, of the square the node's cell covers on screen
 *  (its silhouette seen from the eye at the cell's nearest point; infinite when the eye is in). */
float projectedPixels(
        const storage::NodeRecord& node,
        const glm::vec3& localEye,
        const TransformMetric& metric,
        const Camera& camera,
        float pixelScale);

/** Whether the ε rule draws the node as its cube at `projected` pixels. */
bool drawnAsCube(const storage::NodeRecord& node, float projected, const SelectionOptions& options);

/** The node's cube faces a viewer at `localEye` sees (those whose outer side holds the eye) of
 *  alpha at least `leastAlpha`. */
std::uint32_t cubeFacesToward(
        const storage::NodeRecord& node, const glm::vec3& localEye, std::uint8_t leastAlpha);
/** The same for a cube as drawn (the box [lo, hi] with `faces`, in kCubeFace order). */
std::uint32_t cubeFacesToward(
        const glm::vec3& lo,
        const glm::vec3& hi,
        const std::array<std::array<std::uint8_t, 4>, storage::kCubeFaceCount>& faces,
        const glm::vec3& localEye,
        std::uint8_t leastAlpha);

/** Which of a cell's payloads a walk draws. */
enum class Payload : std::uint8_t {
    Own,        ///< its own triangles (and its children, drawn apart)
    Simplified, ///< its simplified stand-in, instead of its whole subtree
    Splats,     ///< its splats, instead of its whole subtree
    /** its cube: a kind `--representation` forces that the cell did not keep, nor the other
     *  stand-in (the nearest kept one is what the ε rule would draw there) */
    Cube,
};

/**
 * Whether a cell the ε rule refines may be drawn as a stand-in (a simplified copy of its
 * subtree, builder/src/StandIns.h, or splats, builder/src/Splats.h) instead: when the
 * stand-in's error, in the cell's units, is less than ε pixels at the cell's nearest point
 * (times the instance's largest stretch), and for splats when their diameter on screen is at
 * least twice that (no holes); or where `--representation simplified|splats` forces that kind
 * over the cube (splats still only without holes).
 */
struct StandInView {
    bool allowed = false;      ///< `--representation cube` draws none
    bool forced = false;       ///< simplified or splats, where auto would draw the cube
    Representation representation = Representation::Auto;
    float pixelsPerUnit = 0.0f; ///< at the cell's nearest point; infinite with the eye inside
    float epsilonPixels = 0.0f;
    float splatPixels = 0.0f; ///< the splats' diameter on screen

    [[nodiscard]] bool accepts(Payload kind, float error) const noexcept {
        if (!allowed || kind == Payload::Own || kind == Payload::Cube)
            return false;
        const bool splats = kind == Payload::Splats;
        if ((representation == Representation::Simplified && splats) ||
            (representation == Representation::Splats && !splats))
            return false;
        const float onScreen = error * pixelsPerUnit;
        const bool noHoles = !splats || 2.0f * onScreen <= splatPixels;
        return noHoles && (forced || onScreen < epsilonPixels);
    }
    /** The forced kind, where one is (`--representation simplified|splats`). */
    [[nodiscard]] Payload forcedKind() const noexcept {
        return representation == Representation::Splats ? Payload::Splats : Payload::Simplified;
    }
    /** Whether a forced cell that did not keep the forced kind may draw its other stand-in of
     *  `error`: the nearest kept representation, as both promise an error in pixels and the
     *  cube does not. Splats still only without holes. */
    [[nodiscard]] bool acceptsInstead(Payload kind, float error) const noexcept {
        if (!forced || kind == Payload::Own || kind == Payload::Cube || kind == forcedKind())
            return false;
        return kind != Payload::Splats || 2.0f * error * pixelsPerUnit <= splatPixels;
    }
    /** The diameter splats of `error` are drawn at here: twice their error on screen (no
     *  holes, no more bleed past the surface's outline than that), at least a pixel. */
    [[nodiscard]] float splatDiameter(float error) const noexcept {
        return std::clamp(2.0f * error * pixelsPerUnit, 1.0f, splatPixels);
    }
};

/** Whether a frame draws its cubes as area-weighted points (`--cube-draw`), in every pass. */
bool drawsCubesAsPoints(const SelectionOptions& options);

/** What a walk does with a node it reaches, the same in every traversal. */
enum class Verdict { Culled, Cube, Refine };

/** Where a node's frame of reference puts it for the ε rule and the frustum test. */
struct NodeFrame {
    const Frustum& frustum;
    const glm::vec3& localEye;
    const TransformMetric& metric;
};

/** Counts the node as visited (and culled), then: outside the frustum, drawn as its cube, or to
 *  be refined; `projected` gets the ε rule's measure. Reports a reference cycle past
 *  kMaxNesting (Culled). */
Verdict classify(
        const storage::NodeRecord& node,
        const NodeFrame& where,
        const Camera& camera,
        float pixelScale,
        const SelectionOptions& options,
        FrameStats& stats,
        float& projected);

/** The stand-in rule for a node classify() refined, seen from `where` (`projected` its ε
 *  measure). */
StandInView standInView(
        const storage::NodeRecord& node,
        const NodeFrame& where,
        const Camera& camera,
        float pixelScale,
        const SelectionOptions& options,
        float projected);

/** The failure a hierarchy nesting deeper than kMaxNesting reports. */
Status nestingTooDeep();

/** Sorts a batch's geometry by transform and page and merges runs that continue one another
 *  (far fewer draw commands; the same triangles in the same order whatever the walk's order,
 *  so ε = 0 reproduces --method full). Returns the draws left. */
std::size_t mergeGeometryDraws(std::vector<GeometryDraw>& draws);

/** A run of a node's own items in one Geometry page (GeometryDraw's first, count, triangles),
 *  with the page's bytes as resident. */
struct PayloadRun {
    std::uint64_t page;
    const std::byte* payload;
    std::uint32_t first;
    std::uint32_t count;
    std::uint32_t triangles;
    std::uint32_t payloadBytes;
    std::uint32_t points = 0; ///< splats among the items (point clusters' vertices)
    float pointPixels = 0.0f; ///< GeometryDraw::pointPixels
};

enum class Fetch { Ready, Missing };

/**
 * Node and geometry pages as a traversal reads them within one frame: through IPageAccess,
 * never waiting (a page not Ready is Missing and has been asked for), counting misses in the
 * frame's stats, and reporting each failed page once over the traversal's life.
 *
 * Both formats are read into storage::NodeRecord, the record every traversal walks. A format 2
 * node (NodeRecordV2.h) becomes one with its decoded bounds as both boxes (its cube is drawn on
 * them), its first child's page and slot (children are consecutive in one page), its depth as
 * `level`, and, for a cell, its own page, first representation and representation count as
 * geometryPage, geometryFirst and geometryCount (an instance keeps its instance index). A node's
 * bounds decode against its parent's, so children are read through child() with the parent's
 * record, roots through root() and prototypeRoot().
 */
class NodePages {
public:
    NodePages(const storage::SceneIndex& scene, IPageAccess& pages);

    /** Starts a frame: failures met from now on go to newFailures(). */
    void beginFrame() { mNewFailures.clear(); }
    /** Where misses and refused uploads are counted from now on. */
    void countInto(FrameStats& stats) noexcept { mStats = &stats; }

    Fetch
    fetch(std::uint64_t page,
          storage::PageType type,
          float priority,
          std::span<const std::byte>& payload);
    /** The scene's root (the instance level). `subtreeTriangles`, where given, gets what its
     *  subtree draws at full detail (format 2's records carry it; format 1: left as it is). */
    Fetch root(
            float priority,
            storage::NodeRef& ref,
            storage::NodeRecord& out,
            float* subtreeTriangles = nullptr);
    /** The root of prototype `prototype`'s hierarchy. */
    Fetch prototypeRoot(
            std::uint32_t prototype, float priority, storage::NodeRef& ref, storage::NodeRecord& out);
    /** The child page of a node that has children (Ready: `payload` holds it). */
    Fetch
    childPage(const storage::NodeRecord& node, float priority, std::span<const std::byte>& payload);
    /** Child `index` of `parent`, read from its childPage(). Errors: Corrupt (not reported).
     *  `subtreeTriangles` as for root(). */
    [[nodiscard]] Result<storage::NodeRecord> child(
            const storage::NodeRecord& parent,
            std::span<const std::byte> childPage,
            std::uint32_t index,
            float* subtreeTriangles = nullptr) const;
    /** Fills `out` with the node's own payload runs if every page is Ready and admitted by
     *  `uploads` (every page is asked for before answering, so all are in flight together). */
    Fetch collectGeometry(
            const storage::NodeRecord& node,
            float priority,
            IUploadGate& uploads,
            std::vector<PayloadRun>& out);
    /** What a refined cell draws: the runs of the first of its stand-ins (simplified, then
     *  splats) that `view` accepts and whose pages are all resident and admitted (`drawn` says
     *  which: draw them instead of its own payload and children), else collectGeometry()'s
     *  (`drawn` Own; the stand-in's pages stay asked for). Where `view` forces a kind the cell
     *  did not keep, the nearest kept one: its other stand-in, else its cube (`drawn` Cube, no
     *  runs); counted in FrameStats. */
    Fetch collectPayload(
            const storage::NodeRecord& node,
            const StandInView& view,
            float priority,
            IUploadGate& uploads,
            std::vector<PayloadRun>& out,
            Payload& drawn);
    /** collectGeometry() without an upload gate, appending to `out`. */
    Fetch payloadRuns(const storage::NodeRecord& node, float priority, std::vector<PayloadRun>& out);

    /** The scene's prototypes as format 1 records (format 2's roots as page and slot), for
     *  what traversals estimate from their counts and bounds. */
    [[nodiscard]] const std::vector<storage::PrototypeRecord>& prototypes() const noexcept {
        return mPrototypes;
    }

    void reportFailure(const Status& failure);
    [[nodiscard]] const std::vector<Status>& newFailures() const noexcept { return mNewFailures; }
    [[nodiscard]] const storage::SceneIndex& scene() const noexcept { return mScene; }
    [[nodiscard]] FrameStats& stats() noexcept { return *mStats; }

private:
    /** Reads the node at `ref` of a hierarchy's top (bounds relative to `box` in format 2). */
    Fetch readTop(
            storage::NodeRef ref,
            const storage::NodeBox& box,
            float priority,
            storage::NodeRecord& out,
            float* subtreeTriangles = nullptr);
    [[nodiscard]] Result<storage::NodeRecord> decodeV2(
            std::span<const std::byte> payload,
            storage::NodeRef ref,
            const storage::DecodedNodeV2& parent,
            std::uint8_t level,
            float* subtreeTriangles) const;
    /** A format 2 cell's representations into mRepresentations (its own page fetched). */
    Fetch readRepresentations(const storage::NodeRecord& node, float priority);
    /** The runs of its own clusters, or of a stand-in's. */
    Fetch clusterRuns(
            const storage::NodeRecord& node, float priority, std::vector<PayloadRun>& out, Payload which);
    /** The runs of mRepresentations (as readRepresentations() left them) of `which`. */
    Fetch runsOf(float priority, std::vector<PayloadRun>& out, Payload which);
    /** The record of mRepresentations that holds `kind`, or null. */
    [[nodiscard]] const storage::RepresentationRecord* keptOf(Payload kind) const;
    /** `kept`'s runs into `out` if all are resident and admitted (splats sized for `view`);
     *  else `out` empty and Missing (the pages stay asked for). */
    Fetch drawStandIn(
            Payload kind,
            const storage::RepresentationRecord& kept,
            const StandInView& view,
            float priority,
            IUploadGate& uploads,
            std::vector<PayloadRun>& out);
    /** Drops the runs `uploads` refuses (counted; Missing then). */
    Fetch admit(Fetch result, IUploadGate& uploads, std::vector<PayloadRun>& out);

    const storage::SceneIndex& mScene;
    IPageAccess& mPages;
    const bool mV2;
    std::vector<storage::PrototypeRecord> mPrototypes;
    storage::NodeRef mRoot{};
    FrameStats* mStats = nullptr;
    std::unordered_set<std::string> mReported; ///< messages ("page N: ...") already reported
    std::vector<Status> mNewFailures;
    std::vector<storage::GeometrySegment> mRuns; ///< format 1 scratch
    std::vector<storage::RepresentationRecord> mRepresentations; ///< format 2 scratch
};

/** Where the scene's root node is: the header's root (format 1), or its node index's page and
 *  slot (format 2). Errors: Corrupt. */
[[nodiscard]] Result<storage::NodeRef> sceneRoot(const storage::SceneIndex& scene);

} // namespace ff::runtime::detail
