// Occlusion culling with temporal coherence: Mattausch, Bittner, Wimmer, "CHC++: Coherent
// Hierarchical Culling Revisited", Eurographics 2008, on the ε cut of Chamberlain et al. '96,
// with instances, streaming and bounded draw batches. See OcclusionTraversal.h.

#include "NodePages.h"

#include <ff/runtime/BackToFrontTraversal.h>
#include <ff/runtime/Frustum.h>
#include <ff/runtime/OcclusionTraversal.h>
#include <ff/runtime/TransformMetric.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
#include <limits>
#include <optional>
#include <utility>
#include <absl/container/flat_hash_map.h>

namespace ff::runtime {

namespace {

using detail::Fetch;
using detail::toVec3;

double boxArea(const glm::vec3& lo, const glm::vec3& hi) {
    const glm::dvec3 d = glm::max(glm::dvec3(hi - lo), glm::dvec3(0.0));
    return 2.0 * (d.x * d.y + d.y * d.z + d.z * d.x);
}

constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
/** History entries not seen for this many frames are dropped. */
constexpr std::uint32_t kHistoryFrames = 64;
/** Nodes hidden at this many tests in a row are tested together (CHC++'s multiqueries group
 *  the nodes likely to stay hidden; a group found visible costs a test per node again). */
constexpr std::uint16_t kStableHiddenTests = 2;
/** On a frame without history a node is held, too, behind a nearer box wholly in front of it
 *  that shares part of its screen rectangle (the atoms of a dense volume, layer behind layer,
 *  whose boxes never overlap), until the frame has waited this many times for an answer. Every
 *  hold is a round trip through llvmpipe: one-shot frames, against holding by overlapping
 *  boxes only, the 100 k-atom molecule 0.8 s and 2.4 M triangles against 1.7 s and 5-5.8 M,
 *  the city from the street 6 % faster, the cathedral's nave 5-9 % slower and its aisle 4 %
 *  faster; without the limit the forest from inside waited 880 times and took 25 % longer.
 *  With history the nodes in front are mostly drawn untested (visible last frame): held on
 *  every frame, the city's walk waited three times as often (17 a frame against 6) and took
 *  17 % longer. */
constexpr std::uint32_t kHeldBehindWaits = 32;
/** On a frame without history a test pays only in proportion to the chance that it hides
 *  something, and the frame's own answers estimate that chance while nothing that writes depth
 *  has been drawn since they were asked for: against the same depth, the next test is about as
 *  likely to come back hidden. The share found hidden, (hidden + 1) / (answered + 2) (this prior
 *  share, of two answers), weighs what a test may save over the prior share: the frame starts
 *  out testing as a frame with history does, and where tests keep finding everything visible
 *  while what they let through draws no depth (the forest from its corner: trees far enough to
 *  be points, which occlude nothing, over a ground that hides none of them) the nodes below a
 *  test's worth are walked whole untested (5,454 tests against 131 there). Once something is
 *  drawn to depth the answers are forgotten: the dense molecule's atoms draw depth after
 *  every answer and are tested as before. (Kept over answers forgotten only after the depth
 *  grew by a quarter: that halved the molecule's one-shot speed-up, for 10 % from the forest's
 *  edge.) */
constexpr double kPriorHiddenShare = 0.5;
constexpr double kPriorAnswers = 2.0;
/** After a frame whose tests hid less than OcclusionOptions::minHiddenShare of its work, this
 *  many frames are drawn without tests, unless the camera jumps (the view there is new); the
 *  next one is tested with the history they left, late-testing every visible leaf. A tested
 *  frame costs more than a frustum-culled one where nothing is hidden: the forest seen from its
 *  edge, where every tree's box shows some canopy over the row in front, 5-15 % warm; one such
 *  frame in nine should leave about a ninth of that (not measurable yet: docs/methods.md §9).
 *  Tested as a first frame instead, without history, it cost the cathedral's walk more than it
 *  saved: a cold frame there costs a third more than frustum culling's. */
constexpr std::uint32_t kUnpaidFrames = 8;
/** A camera that turned more than this since the last frame, or moved more than this share of
 *  its distance to the scene's centre (at least a tenth of the scene's diagonal, for an eye near
 *  the centre), jumped: what was visible there says little here, and drawn untested it would
 *  stay drawn until its next late test (up to visibleTestInterval frames). The frame after a
 *  jump starts without history, as the first frame does. An orbit of 120 frames a turn moves
 *  about 5 % of its radius a frame; a walk, a few percent. */
constexpr float kJumpDegrees = 30.0f;
constexpr float kJumpShareOfDistance = 0.25f;

bool jumped(const Camera& from, const Camera& to, const glm::vec3& sceneMin, const glm::vec3& sceneMax) {
    const glm::vec3 centre = 0.5f * (sceneMin + sceneMax);
    const float scale = std::max(glm::distance(from.eye, centre), 0.1f * glm::distance(sceneMin, sceneMax));
    return glm::distance(from.eye, to.eye) > kJumpShareOfDistance * scale ||
           glm::dot(from.forward, to.forward) < std::cos(glm::radians(kJumpDegrees));
}

double millisecondsSince(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
            .count();
}

/** What the walk remembers of a node between frames. */
struct History {
    std::uint32_t lastSeen = 0;      ///< frame that last reached it
    std::uint32_t lastVisible = 0;   ///< frame that last drew something of it (0: never)
    std::uint32_t cubesFrame = 0;    ///< frame whose cubes lay below it (pass 2 walks it)
    std::uint32_t occludedFrame = 0; ///< frame whose test found it hidden (pass 2 skips it)
    std::uint16_t hiddenTests = 0;   ///< tests in a row that found it hidden
    bool hidden = false;             ///< its last test found it hidden
    /** Frame that walked its subtree whole (pass 2 asks nothing below it) and, if it kept them
     *  (walkedRecorded), met the cubes [walkedFirst, + walkedCount) of that frame's record
     *  (pass 2 draws them without walking there again). */
    std::uint32_t walkedFrame = 0;
    bool walkedRecorded = false;
    std::uint32_t walkedFirst = 0;
    std::uint32_t walkedCount = 0;
};

class HistoryVisibility final : public IVisibility {
public:
    explicit HistoryVisibility(const absl::flat_hash_map<NodeKey, History, NodeKeyHash>& history)
        : mHistory(history) {}
    [[nodiscard]] Visibility visibility(const NodeKey& key) const override {
        const auto it = mHistory.find(key);
        if (it == mHistory.end())
            return Visibility::Unknown;
        return it->second.hidden ? Visibility::Occluded : Visibility::Visible;
    }

private:
    const absl::flat_hash_map<NodeKey, History, NodeKeyHash>& mHistory;
};

/** What pass 2 skips: the nodes this frame's tests found hidden, and those pass 1 walked whole
 *  without meeting a cube (pass 2 draws cubes only: nothing there for it); and what it takes
 *  as met: the cubes below a subtree pass 1 walked whole. */
class FrameOccluded final : public IVisibility {
public:
    FrameOccluded(
            const absl::flat_hash_map<NodeKey, History, NodeKeyHash>& history,
            const std::vector<MetCube>& met)
        : mHistory(history)
        , mMet(met) {}
    [[nodiscard]] Visibility visibility(const NodeKey& key) const override {
        return known(key).visibility;
    }
    [[nodiscard]] Known known(const NodeKey& key) const override {
        const auto it = mHistory.find(key);
        if (it == mHistory.end() || it->second.lastSeen != mFrame)
            return {}; // pass 1 did not reach it (a cube, or below a drawn node)
        const History& h = it->second;
        if (h.occludedFrame == mFrame || h.cubesFrame != mFrame)
            return {Visibility::Occluded, false, false, {}};
        if (h.walkedFrame != mFrame)
            return {};
        if (!h.walkedRecorded)
            return {Visibility::Unknown, true, false, {}};
        return {Visibility::Unknown, true, true, std::span(mMet).subspan(h.walkedFirst, h.walkedCount)};
    }
    void startFrame(std::uint32_t frame) { mFrame = frame; }

private:
    const absl::flat_hash_map<NodeKey, History, NodeKeyHash>& mHistory;
    const std::vector<MetCube>& mMet;
    std::uint32_t mFrame = 0;
};

} // namespace

struct OcclusionTraversal::Impl {
    /** An instance frame the walk has entered this frame. */
    struct Transform {
        glm::mat4 matrix;
        glm::vec3 localEye;
        TransformMetric metric;
        Frustum frustum;
        std::uint64_t instancePath;
        /** The prototype it places (nullptr: the instance level). */
        const storage::PrototypeRecord* prototype;
        std::uint32_t listBatch; ///< the batch it was last added to (kNone: none yet)
        std::uint32_t listIndex; ///< its index in that batch's transforms
    };
    /** A node waiting in the front-to-back queue. */
    struct Entry {
        storage::NodeRecord record;
        storage::NodeRef ref;
        float distance;  ///< nearest world distance of its bounds from the eye
        float projected; ///< the ε rule's measure, pixels
        std::uint32_t transform;
        std::uint32_t parent; ///< the slot of the node that queued it (kNone: the root)
        std::uint32_t depth;
        float testSaves = 0.0f; ///< testSaves(), when it was queued
        /** What its subtree draws at full detail (format 2's records; negative: format 1's,
         *  which do not say), counted in triangles_occluded when a test hides it. */
        float subtreeTriangles = -1.0f;
        /** Its slot, for a node held back from its test (queueForTest) and queued again. */
        std::uint32_t heldSlot = kNone;
    };
    /** A node the walk reached this frame, for pulling visibility up. */
    struct Slot {
        NodeKey key;
        std::uint32_t parent;
        bool visible;
        bool cubesBelow = false; ///< pass 2 has a cube to draw in its subtree
        bool walked = false;     ///< walked whole
        bool recorded = false;   ///< and its cubes are metCubes[walkedFirst, + count)
        std::uint32_t walkedFirst = 0;
        std::uint32_t walkedCount = 0;
    };
    /** A node waiting for (or in) a test. */
    struct Tested {
        Entry entry;
        std::uint32_t slot;
        float projected;
        /** Its test box (set when it is queued): world bounds, screen rectangle (normalised
         *  device coordinates) and depth range (view space, along the view direction). */
        glm::vec3 worldMin{0.0f};
        glm::vec3 worldMax{0.0f};
        glm::vec2 screenMin{0.0f};
        glm::vec2 screenMax{0.0f};
        float depthMin = 0.0f;
        float depthMax = 0.0f;
    };
    struct Query {
        QueryTicket ticket;
        std::uint32_t first; ///< its nodes: mTested[first, first + count)
        std::uint32_t count;
        std::uint64_t depthDrawn = 0; ///< depthDrawn() when it was issued
    };
    struct LateQuery {
        QueryTicket ticket;
        NodeKey key;
        float saves; ///< testSaves() of the node, counted in hiddenSaves if it is hidden
    };
    /** A late test not issued yet (issueLate()). */
    struct LateTest {
        OcclusionBox box;
        NodeKey key;
        float saves;
    };

    Impl(const storage::SceneIndex& sceneFile, IPageAccess& pages)
        : scene(sceneFile)
        , nodePages(sceneFile, pages)
        , cubes(sceneFile, pages)
        , historyView(history)
        , occluded(history, metCubes) {
        cubes.setCubesOnly(true);
        for (const storage::PrototypeRecord& prototype : nodePages.prototypes())
            mostTrianglesPerNode = std::max(mostTrianglesPerNode, trianglesPerNode(prototype));
    }

    Status traverse(const FrameContext& frame, TraversalServices services, FrameStats& stats);
    /** Whether this frame goes without tests (kUnpaidFrames), counting it if so. */
    bool skipsTests();
    /** The frame as frustum culling draws it: one back-to-front walk, no tests. */
    Status drawUntested();
    /** After a tested frame: whether the next ones go without tests. */
    void judgeFrame();
    /** Whether frames may go untested at all: OcclusionOptions::minHiddenShare is set and the
     *  diagnostics, which measure the tests themselves, are off. */
    bool mayGoUntested() const {
        const OcclusionOptions& options = frame->occlusion;
        return options.minHiddenShare > 0.0f && options.coherent && !options.ignoreAnswers;
    }
    void process(const Entry& entry);
    /** Draws a node found (or taken as) visible: its cube is pass 2's, a refined node's
     *  geometry is drawn and its children queued. `answered`: this frame's test found it
     *  visible, so the next frame knows as much and it needs no late test. */
    void draw(const Tested& node, bool answered = false);
    void refine(const Entry& entry, std::uint32_t slot, float projected, bool answered);
    enum class Expanded { Deferred, NothingOwn, DrewGeometry };
    /** Queues `runs` (a cell's payload) for drawing under `transform`. */
    void drawRuns(std::uint32_t transform);
    /** Expands a visible cell: draws its own geometry and hands each child to `child`. Deferred
     *  (nothing done) when its pages are not all resident or a child is unreadable, or when a
     *  forced representation it did not keep falls back to its cube: its cube stands in for it
     *  (pass 2). */
    template <typename Child>
    Expanded expandCell(
            const storage::NodeRecord& node,
            std::uint32_t transform,
            float priority,
            Child&& child,
            bool nearestFirst = false);
    bool enterInstance(
            const storage::NodeRecord& node,
            std::uint32_t parentTransform,
            float priority,
            std::uint32_t& transform,
            storage::NodeRef& rootRef,
            storage::NodeRecord& root);
    /** Draws a subtree too small to test, without tests or history, and records the cubes it
     *  meets for pass 2 (MetCube). */
    void walkWhole(const Entry& entry, std::uint32_t slot);
    /** walkWhole's walk: depth first, nearest child first. */
    void drawSubtree(const storage::NodeRecord& node, std::uint32_t transform, std::uint32_t depth);
    /** The triangles a test of the node may save: what its subtree draws, estimated. */
    double testSaves(const Entry& entry) const;
    /** The most a subtree seen this small draws where it is cut at ε, as a surface: (size / ε)²
     *  cells of `perNode` triangles each (unbounded at ε = 0). */
    double cutTriangles(const Entry& entry, double perNode) const;
    /** Whether a test that may save this many triangles pays for itself
     *  (OcclusionOptions::minTestTriangles). */
    bool paysForTest(double saves) const {
        return saves >= static_cast<double>(frame->occlusion.minTestTriangles);
    }
    /** How likely a test is to find a node hidden, against kPriorHiddenShare (1: as likely,
     *  less: less likely); what a test may save is weighed by it. */
    double hiddenLikelihood() const;
    static double trianglesPerNode(const storage::PrototypeRecord& prototype) {
        return std::max(
                1.0,
                static_cast<double>(prototype.triangleCount) /
                        static_cast<double>(std::max<std::uint64_t>(prototype.nodeCount, 1)));
    }
    /** Triangles below the node, estimated from its prototype's count and its level. */
    std::uint64_t estimatedTriangles(const Entry& entry) const;
    /** The prototype whose hierarchy the node is in, or an instance node places (nullptr: a
     *  cell of the instance level). */
    const storage::PrototypeRecord* prototypeBelow(const Entry& entry) const;
    void reportCycle();
    detail::Verdict classify(const storage::NodeRecord& node, const Transform& t, float& projected);
    void queueForTest(Tested node);
    /** Whether a nearer node whose box overlaps the node's is still waiting for its answer: if
     *  that one is visible, what it draws may hide this one, and a test issued now would not
     *  see it (a building's furniture tested beside its walls). */
    bool behindUnanswered(const Tested& node) const;
    /** Held nodes no unanswered node stands in front of any more, back into the queue. */
    void releaseHeld();
    void issueQueued();
    void answer(const Query& query, bool visible);
    void testLate(const Entry& entry, std::uint32_t slot);
    bool testable(const Entry& entry, OcclusionBox& box) const;
    void pushChild(
            const storage::NodeRecord& record,
            storage::NodeRef ref,
            float subtreeTriangles,
            std::uint32_t transform,
            std::uint32_t parent,
            std::uint32_t depth);
    std::uint32_t addTransform(
            const glm::mat4& matrix,
            std::uint64_t instancePath,
            const storage::PrototypeRecord* prototype);
    std::uint32_t listIndex(std::uint32_t transform);
    void markVisible(std::uint32_t slot);
    /** A cube (or a deferred node's) for pass 2 below currentSlot: pulled up like visibility.
     *  Drawn here too, as an occluder, where it can occlude (OcclusionOptions::cubesOcclude).
     *  `deferred`: the node's pages are not ready (pass 2 draws its cube if it has one). */
    void sawCube(const storage::NodeRecord& node, std::uint32_t transform, bool deferred = false);
    /** walkWhole's record of a cube pass 2 would draw. */
    void recordMet(const storage::NodeRecord& node, std::uint32_t transform, bool deferred);
    void flush();
    /** Pass 1's slots into the history (before pass 2, which reads what had cubes below). */
    void rememberSlots();
    /** The late answers into the history; old entries dropped. */
    void finishFrame();
    /** What pass 1 has drawn that writes depth: what a test can be hidden by. */
    std::uint64_t depthDrawn() const { return stats->trianglesDrawn + stats->occluderCubes; }
    bool budgetLeft() const { return stats->occlusionQueries < frame->occlusion.queryBudget; }
    /** Issues the late tests, after pass 1, with what is left of the frame's test budget. */
    void issueLate();
    QueryTicket issue(std::span<const OcclusionBox> boxes);
    /** The queue's order: a max-heap on this is a min-heap on distance. */
    static bool farther(const Entry& a, const Entry& b) { return a.distance > b.distance; }

    const storage::SceneIndex& scene;
    detail::NodePages nodePages;
    BackToFrontTraversal cubes; ///< pass 2
    /** Open addressing: it is looked up for every node both passes reach, and with
     *  std::unordered_map (an allocation per entry) the lookups were the top symbol of the
     *  forest's edge view (10.6 % of its samples in perf; 2.4 % with this map). */
    absl::flat_hash_map<NodeKey, History, NodeKeyHash> history;
    std::optional<Camera> lastCamera; ///< the last tested frame's (jumped())
    /** Frames still to be drawn without tests: the last tested one hid too little (kUnpaidFrames). */
    std::uint32_t untestedFramesLeft = 0;
    bool lastUntested = false; ///< the last frame went without tests
    double mostTrianglesPerNode = 1.0; ///< the largest trianglesPerNode() of the prototypes
    HistoryVisibility historyView;
    FrameOccluded occluded;
    std::vector<Status> failures; ///< both passes' new failures
    std::uint32_t frameNumber = 0;

    /** What a redrawable frame started from (beginRedrawableFrame()). */
    struct FrameStart {
        absl::flat_hash_map<NodeKey, History, NodeKeyHash> history;
        std::optional<Camera> lastCamera;
        std::uint32_t frameNumber = 0;
        std::uint32_t untestedFramesLeft = 0;
        bool lastUntested = false;
    };
    bool redrawable = false;
    bool redraw = false;
    std::optional<FrameStart> frameStart;

    // Per-frame state.
    const FrameContext* frame = nullptr;
    TraversalServices* services = nullptr;
    FrameStats* stats = nullptr;
    float pixelScale = 1.0f;
    glm::mat4 view{1.0f};
    glm::mat4 viewProjection{1.0f};
    bool depthWritten = false; ///< some geometry reached GL this frame: tests have occluders
    bool withoutHistory = false; ///< the first frame or one after a jump
    std::uint32_t waits = 0;     ///< answers waited for this frame
    /** The frames before this one went without tests, from this one's history: it late-tests
     *  every visible leaf, not an interval's share, to judge with all of them (judgeFrame()). */
    bool afterUntested = false;
    /** What the nodes this frame's tests (late ones too) hid would have drawn (testSaves(),
     *  summed). */
    double hiddenSaves = 0.0;
    /** On a frame without history: nodes answered since the depth drawn last changed
     *  (kPriorHiddenShare), and how many of them were hidden. */
    std::uint32_t coldAnswers = 0;
    std::uint32_t coldHidden = 0;
    std::uint64_t evidenceDepth = 0; ///< depthDrawn() of the first test they count
    std::uint32_t batchNumber = 0;
    DrawList list;
    std::vector<Transform> transforms;
    std::vector<Entry> queue; ///< a min-heap on distance
    std::vector<Slot> slots;
    std::vector<Tested> waiting; ///< queued for the next batch of tests
    std::vector<Tested> held;    ///< held back from their tests (behindUnanswered)
    bool answeredSinceRelease = false; ///< some answer came since releaseHeld() last looked
    std::vector<Tested> tested;  ///< in a test (Query ranges point here)
    std::deque<Query> pending;
    std::vector<LateQuery> late;
    /** Late tests not yet issued. They go after pass 1, against all of its depth (issued at
     *  once, they saw only the batches flushed before them, and a batch holds up to hundreds of
     *  thousands of occluder cubes), and only with the budget this frame's own tests left: they
     *  are for the next frame, and one taken from a node still waiting for its answer has it
     *  drawn untested now (the 100 k-atom molecule's cold frame spends the whole budget). */
    std::vector<LateTest> lateWaiting;
    std::vector<detail::PayloadRun> runs;
    struct ChildRecord {
        storage::NodeRecord record;
        storage::NodeRef ref;
        float subtreeTriangles;
        float distance; ///< of its cell's centre, squared (set only for a nearest-first walk)
        std::uint32_t index;
    };
    /** The subtree walkWhole is walking: pass 2 may take its cubes as met only if they lie in
     *  the frame of its root or of the one instance its root places. */
    struct WholeWalk {
        bool recording = false;
        bool complete = true;
        std::uint32_t outer = kNone; ///< the root's transform
        std::uint32_t inner = kNone; ///< the transform of the instance the root places
        std::uint32_t rootDepth = 0;
        std::uint64_t deferred = 0; ///< deferred nodes met (counted once the record is taken)
    } wholeWalk;
    /** The cubes walkWhole met this frame, each subtree's back to front (FrameOccluded). */
    std::vector<MetCube> metCubes;
    std::size_t metCubesLimit = 0; ///< FrameBudgets::drawBatchBytes' worth
    std::vector<ChildRecord> children; ///< expandCell's stack of decoded children
    bool cubesSeen = false;            ///< pass 1 met a node drawn as its cube: pass 2 has work
    Status sinkStatus;                 ///< the first error the renderer reported this frame
    std::uint32_t currentSlot = kNone; ///< the slotted node whose subtree pass 1 is expanding
    /** Children met that will not be tested on their own (cubes, subtrees too small to test):
     *  a count, so refine() can tell whether a node's children were among them. */
    std::uint64_t untestedMet = 0;
    std::vector<OcclusionBox> boxes;
};

OcclusionTraversal::OcclusionTraversal(const storage::SceneIndex& scene, IPageAccess& pages)
    : mImpl(std::make_unique<Impl>(scene, pages)) {}
OcclusionTraversal::~OcclusionTraversal() = default;

Status OcclusionTraversal::traverse(
        const FrameContext& frame, TraversalServices services, FrameStats& stats) {
    return mImpl->traverse(frame, services, stats);
}

const std::vector<Status>& OcclusionTraversal::newFailures() const noexcept {
    return mImpl->failures;
}

const IVisibility& OcclusionTraversal::history() const noexcept {
    return mImpl->historyView;
}

void OcclusionTraversal::beginRedrawableFrame() noexcept {
    mImpl->redrawable = true;
    mImpl->redraw = false;
    mImpl->frameStart.reset();
}

void OcclusionTraversal::redrawLastFrame() noexcept {
    mImpl->redraw = mImpl->redrawable;
}

void OcclusionTraversal::endRedrawableFrame() noexcept {
    mImpl->redrawable = false;
    mImpl->redraw = false;
    mImpl->frameStart.reset();
}

Status OcclusionTraversal::Impl::traverse(
        const FrameContext& frameContext, TraversalServices frameServices, FrameStats& frameStats) {
    if (!frameServices.occlusion || frameContext.selection.method != Method::Hierarchical)
        return Status(
                ErrorCode::InvalidArgument,
                "occlusion culling needs an occlusion tester and the hierarchical method");
    frame = &frameContext;
    services = &frameServices;
    stats = &frameStats;
    if (redraw && frameStart) {
        history = frameStart->history;
        lastCamera = frameStart->lastCamera;
        frameNumber = frameStart->frameNumber;
        untestedFramesLeft = frameStart->untestedFramesLeft;
        lastUntested = frameStart->lastUntested;
    } else if (redrawable && !frameStart) {
        frameStart = FrameStart{history, lastCamera, frameNumber, untestedFramesLeft, lastUntested};
    }
    redraw = false;
    const bool untestedBefore = std::exchange(lastUntested, skipsTests());
    if (lastUntested)
        return drawUntested();
    ++frameNumber;
    const storage::FileHeader& header = scene.header();
    if (lastCamera && jumped(*lastCamera, frame->camera, toVec3(header.boundsMin), toVec3(header.boundsMax)))
        history.clear();
    lastCamera = frame->camera;
    withoutHistory = history.empty();
    afterUntested = untestedBefore && !withoutHistory;
    waits = 0;
    hiddenSaves = 0.0;
    coldAnswers = 0;
    coldHidden = 0;
    evidenceDepth = 0;
    nodePages.beginFrame();
    nodePages.countInto(frameStats);
    failures.clear();
    occluded.startFrame(frameNumber);
    pixelScale = frame->camera.pixelScale(static_cast<float>(frame->height));
    const float aspect =
            static_cast<float>(frame->width) / std::max(static_cast<float>(frame->height), 1.0f);
    view = frame->camera.view();
    viewProjection = frame->camera.projection(aspect) * view;
    depthWritten = false;
    cubesSeen = false;
    sinkStatus = Status::ok();
    list.clear();
    list.cubesAsPoints = detail::drawsCubesAsPoints(frame->selection);
    list.splats = frame->selection.splats;
    list.cubesOcclude = true;
    transforms.clear();
    queue.clear();
    slots.clear();
    waiting.clear();
    held.clear();
    answeredSinceRelease = false;
    tested.clear();
    pending.clear();
    late.clear();
    lateWaiting.clear();
    metCubes.clear();
    metCubesLimit = frame->budgets.drawBatchBytes / sizeof(MetCube);
    metCubes.reserve(metCubesLimit);
    ++batchNumber;

    // Pass 1: opaque geometry, front to back, with occlusion tests.
    addTransform(glm::mat4(1.0f), 0, nullptr);
    storage::NodeRef rootRef{};
    storage::NodeRecord root{};
    float rootTriangles = -1.0f;
    if (nodePages.root(detail::kTopPriority, rootRef, root, &rootTriangles) != Fetch::Ready) {
        failures = nodePages.newFailures();
        if (!failures.empty())
            return failures.front().withContext("the root node is unreadable");
        return Status::ok(); // not resident yet: nothing to draw this frame
    }
    pushChild(root, rootRef, rootTriangles, 0, kNone, 0);
    IOcclusionTester& tester = *services->occlusion;
    while (!queue.empty() || !waiting.empty() || !pending.empty() || !held.empty()) {
        // Answers that have arrived; when there is nothing else to do, wait for the oldest.
        while (!pending.empty()) {
            const auto asked = std::chrono::steady_clock::now();
            const bool idle = queue.empty() && waiting.empty();
            if (!idle && !tester.ready(pending.front().ticket)) {
                stats->occlusionMs += millisecondsSince(asked);
                break;
            }
            if (idle && !tester.ready(pending.front().ticket)) {
                ++stats->queriesWaited;
                ++waits;
            }
            const Query query = pending.front();
            pending.pop_front();
            const bool visible = tester.anyVisible(query.ticket);
            stats->occlusionMs += millisecondsSince(asked);
            answer(query, visible);
        }
        if (!held.empty() &&
            (answeredSinceRelease || (queue.empty() && waiting.empty() && pending.empty())))
            releaseHeld();
        if (queue.empty()) {
            if (!waiting.empty())
                issueQueued();
            continue;
        }
        std::pop_heap(queue.begin(), queue.end(), farther);
        const Entry entry = queue.back();
        queue.pop_back();
        process(entry);
        // Without history (the first frame, a jump): once the nearest geometry is known, draw
        // it, so what follows has occluders to be tested against.
        if (!depthWritten && (!list.geometry.empty() || !list.cubes.empty()))
            flush();
        if (waiting.size() >= std::max<std::uint32_t>(frame->occlusion.batchNodes, 1))
            issueQueued();
    }
    flush();
    issueLate();

    rememberSlots();
    // Pass 2: the cubes, back to front, skipping what pass 1 found hidden or walked cube-free.
    FrameStats cubeStats;
    const Status drawn =
            cubesSeen ? cubes.traverse(
                                *frame, {services->sink, occluded, services->uploads}, cubeStats)
                      : Status::ok();
    stats->cubesDrawn += cubeStats.cubesDrawn;
    stats->cubeFacesDrawn += cubeStats.cubeFacesDrawn;
    stats->nodesDeferred += cubeStats.nodesDeferred;
    if (stats->cubeFacesPerLevel.size() < cubeStats.cubeFacesPerLevel.size())
        stats->cubeFacesPerLevel.resize(cubeStats.cubeFacesPerLevel.size(), 0);
    for (std::size_t level = 0; level < cubeStats.cubeFacesPerLevel.size(); ++level)
        stats->cubeFacesPerLevel[level] += cubeStats.cubeFacesPerLevel[level];
    stats->drawMs += cubeStats.drawMs;

    // The late answers (for the next frame) and the history.
    const auto asked = std::chrono::steady_clock::now();
    finishFrame();
    stats->occlusionMs += millisecondsSince(asked);
    judgeFrame();
    failures = nodePages.newFailures();
    for (const Status& failure : cubes.newFailures())
        if (std::find_if(failures.begin(), failures.end(), [&](const Status& f) {
                return f.message() == failure.message();
            }) == failures.end())
            failures.push_back(failure);
    return sinkStatus.isOk() ? drawn : sinkStatus;
}

std::uint32_t OcclusionTraversal::Impl::addTransform(
        const glm::mat4& matrix,
        std::uint64_t instancePath,
        const storage::PrototypeRecord* prototype) {
    const glm::vec3 localEye = glm::vec3(glm::inverse(matrix) * glm::vec4(frame->camera.eye, 1.0f));
    transforms.push_back(
            {matrix,
             localEye,
             TransformMetric(matrix),
             Frustum(viewProjection * matrix),
             instancePath,
             prototype,
             kNone,
             0});
    return static_cast<std::uint32_t>(transforms.size() - 1);
}

std::uint32_t OcclusionTraversal::Impl::listIndex(std::uint32_t transform) {
    Transform& t = transforms[transform];
    if (t.listBatch != batchNumber) {
        t.listBatch = batchNumber;
        t.listIndex = static_cast<std::uint32_t>(list.transforms.size());
        list.transforms.push_back(t.matrix);
        list.localEyes.push_back(t.localEye);
    }
    return t.listIndex;
}

void OcclusionTraversal::Impl::flush() {
    if (list.geometry.empty() && list.cubes.empty())
        return;
    stats->geometryDraws += detail::mergeGeometryDraws(list.geometry);
    if (const Status status = services->sink.draw(list, *stats); !status && sinkStatus.isOk())
        sinkStatus = status; // the frame is finished, then the error returned (as back to front)
    list.clear();
    ++batchNumber;
    depthWritten = true;
}

void OcclusionTraversal::Impl::pushChild(
        const storage::NodeRecord& record,
        storage::NodeRef ref,
        float subtreeTriangles,
        std::uint32_t transform,
        std::uint32_t parent,
        std::uint32_t depth) {
    // The frustum and the ε rule are decided here, not when the node leaves the queue: most
    // nodes of a far field are culled or cubes, and those never enter it.
    const Transform& t = transforms[transform];
    float projected = 0.0f;
    const detail::Verdict verdict = classify(record, t, projected);
    if (verdict == detail::Verdict::Culled)
        return;
    if (verdict == detail::Verdict::Cube) {
        // Pass 2 draws it. A cube costs less to draw than to test and writes no depth: it is
        // neither tested nor remembered, only seen (its parent stays visible).
        currentSlot = parent;
        sawCube(record, transform);
        markVisible(parent);
        ++untestedMet;
        return;
    }
    const float distance = t.metric.nearestDistance(
            toVec3(record.boundsMin), toVec3(record.boundsMax), t.localEye);
    queue.push_back({record, ref, distance, projected, transform, parent, depth});
    queue.back().testSaves = static_cast<float>(testSaves(queue.back()));
    queue.back().subtreeTriangles = subtreeTriangles;
    if (!paysForTest(queue.back().testSaves))
        ++untestedMet; // drawn whole when it leaves the queue
    std::push_heap(queue.begin(), queue.end(), farther);
}

void OcclusionTraversal::Impl::recordMet(
        const storage::NodeRecord& node, std::uint32_t transform, bool deferred) {
    // Bounded like a draw batch (and reserved whole, so it is never copied to grow): past the
    // bound pass 2 walks the subtree itself.
    if (metCubes.size() >= metCubesLimit ||
        (transform != wholeWalk.outer && transform != wholeWalk.inner)) {
        wholeWalk.complete = false;
        return;
    }
    // As the back-to-front walk counts and draws it: a deferred node counted, its cube drawn if
    // it has one.
    if (deferred)
        ++wholeWalk.deferred;
    if (deferred && !(node.flags & storage::kNodeHasCube))
        return;
    metCubes.push_back(
            {{toVec3(node.cellMin), toVec3(node.cellMax), transform == wholeWalk.outer ? 0u : 1u, node.cube},
             static_cast<std::uint8_t>(detail::cubeFacesToward(node, transforms[transform].localEye, 1)),
             node.level});
}

void OcclusionTraversal::Impl::sawCube(
        const storage::NodeRecord& node, std::uint32_t transform, bool deferred) {
    if (wholeWalk.recording && wholeWalk.complete)
        recordMet(node, transform, deferred);
    cubesSeen = true;
    for (std::uint32_t slot = currentSlot; slot != kNone && !slots[slot].cubesBelow;
         slot = slots[slot].parent)
        slots[slot].cubesBelow = true;
    // At threshold 0 only a face of alpha 1 can occlude; above it translucent faces add up.
    const std::uint8_t leastAlpha = frame->occlusion.opacityThreshold > 0.0f ? 1 : 255;
    if (!frame->occlusion.cubesOcclude ||
        detail::cubeFacesToward(node, transforms[transform].localEye, leastAlpha) == 0)
        return;
    // Met front to back (roughly: by its parent's distance), so the opacity it adds in pass 1
    // is composited in about the order pass 2 composites its color in.
    list.cubes.push_back(
            {toVec3(node.cellMin), toVec3(node.cellMax), listIndex(transform), node.cube});
    ++stats->occluderCubes;
    if (list.bytes() >= frame->budgets.drawBatchBytes)
        flush();
}


void OcclusionTraversal::Impl::markVisible(std::uint32_t slot) {
    while (slot != kNone && !slots[slot].visible) {
        slots[slot].visible = true;
        slot = slots[slot].parent;
    }
}

void OcclusionTraversal::Impl::process(const Entry& entry) {
    if (entry.depth > static_cast<std::uint32_t>(detail::kMaxNesting)) {
        reportCycle();
        return;
    }
    const storage::NodeRecord& node = entry.record;
    const Transform& t = transforms[entry.transform];
    const float projected = entry.projected;
    if (entry.heldSlot != kNone) {
        currentSlot = entry.heldSlot;
        queueForTest({entry, entry.heldSlot, projected});
        return;
    }
    const NodeKey key{t.instancePath, entry.ref};
    const auto slot = static_cast<std::uint32_t>(slots.size());
    slots.push_back({key, entry.parent, false});
    const Tested visit{entry, slot, projected};
    currentSlot = slot;
    // Decided here, not when it was queued: what was drawn since, and the answers that came,
    // change how likely a test is to hide it (kPriorHiddenShare). Where a test is less likely
    // to hide something than the prior says, the instance level's cells are taken as surfaces
    // too, (size / ε)² cells of the densest prototype's triangles per node: without that bound
    // they would be worth a test however unlikely it is to pay (the forest's tree groups).
    double saves = entry.testSaves;
    if (const double likelihood = hiddenLikelihood(); likelihood < 1.0 && paysForTest(saves))
        saves = std::min(saves, cutTriangles(entry, mostTrianglesPerNode)) * likelihood;
    if (!paysForTest(saves)) {
        // Too little below it to pay for a test: drawn whole, without tests or history.
        markVisible(slot);
        walkWhole(entry, slot);
        return;
    }
    // A prototype's root has its instance's box: the instance node was the test.
    const bool prototypeRoot = node.level == 0 && t.prototype != nullptr;
    const auto it = history.find(key);
    const bool visibleLastFrame = frame->occlusion.coherent && it != history.end() &&
                                  it->second.lastVisible + 1 >= frameNumber;
    if (visibleLastFrame || prototypeRoot)
        draw(visit);
    else
        queueForTest(visit);
}

void OcclusionTraversal::Impl::draw(const Tested& node, bool answered) {
    currentSlot = node.slot;
    refine(node.entry, node.slot, node.projected, answered);
}

bool OcclusionTraversal::Impl::testable(const Entry& entry, OcclusionBox& box) const {
    const storage::NodeRecord& node = entry.record;
    const Transform& t = transforms[entry.transform];
    // The box that holds all the node can draw: its geometry below and, where the ε rule draws
    // cubes, the cells of its cubes. At ε = 0 a cube only stands in for geometry not resident
    // yet, which lies in the tight bounds: if they are hidden, so is what it stands for. (An
    // octree's cell reaches far past a building's walls, above its roof, where the street's
    // facades do not hide it.)
    glm::vec3 lo = toVec3(node.boundsMin);
    glm::vec3 hi = toVec3(node.boundsMax);
    if (frame->selection.epsilonPixels > 0.0f) {
        lo = glm::min(lo, toVec3(node.cellMin));
        hi = glm::max(hi, toVec3(node.cellMax));
    }
    // Grown a little, so a surface drawn exactly on the box's face does not hide the box from
    // itself by a rounding of its depth.
    const glm::vec3 extent = hi - lo;
    const float grow =
            1e-3f * std::max({extent.x, extent.y, extent.z}) + 1e-6f * std::max(
                                                                               {std::abs(lo.x),
                                                                                std::abs(lo.y),
                                                                                std::abs(lo.z),
                                                                                std::abs(hi.x),
                                                                                std::abs(hi.y),
                                                                                std::abs(hi.z)});
    lo -= glm::vec3(grow);
    hi += glm::vec3(grow);
    // And by ε + 1 pixels on screen wherever in the box (at its farthest point, where a world
    // unit is fewest pixels): a cube below it may be drawn as a point sprite, a square that
    // reaches past its cell's silhouette by up to ε pixels.
    float farthest = frame->camera.zNear;
    for (int c = 0; c < 8; ++c) {
        const glm::vec3 local{(c & 1) ? hi.x : lo.x, (c & 2) ? hi.y : lo.y, (c & 4) ? hi.z : lo.z};
        farthest = std::max(farthest, -(view * (t.matrix * glm::vec4(local, 1.0f))).z);
    }
    const float pixelsOut = frame->selection.epsilonPixels + 1.0f;
    const float worldOut =
            frame->camera.orthographic ? pixelsOut / pixelScale : pixelsOut * farthest / pixelScale;
    glm::vec3 axes[3];
    for (int a = 0; a < 3; ++a) {
        const glm::vec3 axis(t.matrix[a]);
        const float length = glm::length(axis);
        axes[a] = length > 0.0f ? axis * (worldOut / length) : glm::vec3(0.0f);
    }
    const float nearLimit = frame->camera.zNear * 1.001f;
    for (int c = 0; c < 8; ++c) {
        const glm::vec3 local{(c & 1) ? hi.x : lo.x, (c & 2) ? hi.y : lo.y, (c & 4) ? hi.z : lo.z};
        glm::vec4 world = t.matrix * glm::vec4(local, 1.0f);
        for (int a = 0; a < 3; ++a)
            world += glm::vec4((c >> a) & 1 ? axes[a] : -axes[a], 0.0f);
        box.corners[static_cast<std::size_t>(c)] = glm::vec3(world);
        // A box that reaches the near plane is clipped there: its samples say nothing.
        if (-(view * world).z < nearLimit)
            return false;
    }
    // The tester draws front faces only, counter-clockwise seen from outside: a mirroring
    // transform turns the corners' order around, so swap them back along x.
    if (glm::determinant(glm::mat3(t.matrix)) < 0.0f)
        for (std::size_t c = 0; c < 8; c += 2)
            std::swap(box.corners[c], box.corners[c + 1]);
    // A test rasterises its box: one that covers more pixels than the triangles it may save
    // are worth costs more than it can gain (its screen rectangle bounds what it covers).
    glm::vec2 lo2(INFINITY);
    glm::vec2 hi2(-INFINITY);
    for (const glm::vec3& corner : box.corners) {
        const glm::vec4 clip = viewProjection * glm::vec4(corner, 1.0f);
        const glm::vec2 ndc = glm::vec2(clip) / clip.w;
        lo2 = glm::min(lo2, ndc);
        hi2 = glm::max(hi2, ndc);
    }
    lo2 = glm::clamp(lo2, glm::vec2(-1.0f), glm::vec2(1.0f));
    hi2 = glm::clamp(hi2, glm::vec2(-1.0f), glm::vec2(1.0f));
    const glm::vec2 pixels = 0.5f * (hi2 - lo2) * glm::vec2(frame->width, frame->height);
    const double area = static_cast<double>(pixels.x) * static_cast<double>(pixels.y);
    return area <= static_cast<double>(estimatedTriangles(entry)) *
                           static_cast<double>(frame->occlusion.testPixelsPerTriangle);
}

QueryTicket OcclusionTraversal::Impl::issue(std::span<const OcclusionBox> group) {
    ++stats->occlusionQueries;
    return services->occlusion->issue(group);
}

void OcclusionTraversal::Impl::queueForTest(Tested node) {
    // Nothing to test against yet (the first occluders are being drawn), the box reaches the
    // eye, or the frame's tests are spent: the node is Unknown, and Unknown is drawn.
    OcclusionBox box;
    const auto it = history.find(slots[node.slot].key);
    const bool hiddenBefore = it != history.end() && it->second.hidden;
    if ((!depthWritten && !hiddenBefore) || !budgetLeft() || !testable(node.entry, box)) {
        draw(node);
        return;
    }
    node.worldMin = glm::vec3(INFINITY);
    node.worldMax = glm::vec3(-INFINITY);
    node.screenMin = glm::vec2(INFINITY);
    node.screenMax = glm::vec2(-INFINITY);
    node.depthMin = INFINITY;
    node.depthMax = -INFINITY;
    for (const glm::vec3& corner : box.corners) {
        node.worldMin = glm::min(node.worldMin, corner);
        node.worldMax = glm::max(node.worldMax, corner);
        if (!withoutHistory)
            continue; // behindUnanswered() reads the rest only on such a frame
        const glm::vec4 clip = viewProjection * glm::vec4(corner, 1.0f);
        const glm::vec2 ndc = glm::vec2(clip) / clip.w; // in front of the eye: testable()
        node.screenMin = glm::min(node.screenMin, ndc);
        node.screenMax = glm::max(node.screenMax, ndc);
        const float depth = -(view * glm::vec4(corner, 1.0f)).z;
        node.depthMin = std::min(node.depthMin, depth);
        node.depthMax = std::max(node.depthMax, depth);
    }
    if (behindUnanswered(node)) {
        held.push_back(node);
        return;
    }
    waiting.push_back(node);
}

bool OcclusionTraversal::Impl::behindUnanswered(const Tested& node) const {
    const auto inFront = [&](const Tested& other) {
        if (!(other.entry.distance < node.entry.distance))
            return false;
        if (glm::all(glm::lessThanEqual(other.worldMin, node.worldMax)) &&
            glm::all(glm::lessThanEqual(node.worldMin, other.worldMax)))
            return true; // the boxes overlap
        // Wholly in front of it on screen, a nearer box may hide it too: on a frame without
        // history, until kHeldBehindWaits.
        if (!withoutHistory || waits >= kHeldBehindWaits || other.depthMax > node.depthMin)
            return false;
        return glm::all(glm::lessThanEqual(other.screenMin, node.screenMax)) &&
               glm::all(glm::lessThanEqual(node.screenMin, other.screenMax));
    };
    if (std::any_of(waiting.begin(), waiting.end(), inFront))
        return true;
    for (const Query& query : pending)
        for (std::uint32_t i = 0; i < query.count; ++i)
            if (inFront(tested[query.first + i]))
                return true;
    return false;
}

void OcclusionTraversal::Impl::releaseHeld() {
    answeredSinceRelease = false;
    // Queued again rather than tested now: what the answered node draws is queued too (its
    // children), and may stand in front of a held node again.
    std::erase_if(held, [&](const Tested& node) {
        if (behindUnanswered(node))
            return false;
        queue.push_back(node.entry);
        queue.back().heldSlot = node.slot;
        std::push_heap(queue.begin(), queue.end(), farther);
        return true;
    });
}

void OcclusionTraversal::Impl::issueQueued() {
    // The tests see everything drawn so far.
    flush();
    const auto start = std::chrono::steady_clock::now();
    const std::uint32_t groupLimit = std::max<std::uint32_t>(frame->occlusion.multiqueryNodes, 1);
    // Nodes that stayed hidden go first, in groups; the others one by one.
    std::stable_partition(waiting.begin(), waiting.end(), [&](const Tested& t) {
        const auto it = history.find(slots[t.slot].key);
        return it != history.end() && it->second.hidden &&
               it->second.hiddenTests >= kStableHiddenTests;
    });
    std::size_t i = 0;
    while (i < waiting.size()) {
        const auto it = history.find(slots[waiting[i].slot].key);
        const bool stable = it != history.end() && it->second.hidden &&
                            it->second.hiddenTests >= kStableHiddenTests;
        std::size_t end = i + 1;
        if (stable) {
            while (end < waiting.size() && end - i < groupLimit) {
                const auto next = history.find(slots[waiting[end].slot].key);
                if (next == history.end() || !next->second.hidden ||
                    next->second.hiddenTests < kStableHiddenTests)
                    break;
                ++end;
            }
        }
        if (!budgetLeft()) {
            // Out of tests: the rest are Unknown, drawn.
            for (std::size_t j = i; j < waiting.size(); ++j)
                draw(waiting[j]);
            break;
        }
        boxes.clear();
        const auto first = static_cast<std::uint32_t>(tested.size());
        for (std::size_t j = i; j < end; ++j) {
            OcclusionBox box;
            (void)testable(waiting[j].entry, box); // checked when queued
            boxes.push_back(box);
            tested.push_back(waiting[j]);
        }
        pending.push_back({issue(boxes), first, static_cast<std::uint32_t>(end - i), depthDrawn()});
        i = end;
    }
    waiting.clear();
    services->occlusion->submit();
    stats->occlusionMs += millisecondsSince(start);
}

void OcclusionTraversal::Impl::answer(const Query& query, bool visible) {
    visible = visible || frame->occlusion.ignoreAnswers;
    if (visible && query.count > 1) {
        // A group that did not stay hidden: each node is tested on its own.
        const auto start = std::chrono::steady_clock::now();
        for (std::uint32_t i = 0; i < query.count; ++i) {
            const Tested node = tested[query.first + i];
            History& h = history[slots[node.slot].key];
            h.hiddenTests = 0; // no longer grouped
            if (!budgetLeft()) {
                draw(node);
                continue;
            }
            OcclusionBox box;
            (void)testable(node.entry, box);
            const auto first = static_cast<std::uint32_t>(tested.size());
            tested.push_back(node);
            pending.push_back({issue({&box, 1}), first, 1, depthDrawn()});
        }
        services->occlusion->submit();
        stats->occlusionMs += millisecondsSince(start);
        return;
    }
    answeredSinceRelease = true;
    if (withoutHistory) {
        if (query.depthDrawn != evidenceDepth) {
            coldAnswers = 0;
            coldHidden = 0;
            evidenceDepth = query.depthDrawn;
        }
        coldAnswers += query.count;
        coldHidden += visible ? 0 : query.count;
    }
    for (std::uint32_t i = 0; i < query.count; ++i) {
        const Tested node = tested[query.first + i];
        History& h = history[slots[node.slot].key];
        h.lastSeen = frameNumber;
        if (visible) {
            h.hidden = false;
            h.hiddenTests = 0;
            draw(node, !frame->occlusion.ignoreAnswers);
        } else {
            h.hidden = true;
            h.hiddenTests = static_cast<std::uint16_t>(
                    std::min<int>(h.hiddenTests + 1, std::numeric_limits<std::uint16_t>::max()));
            ++stats->nodesOccluded;
            hiddenSaves += node.entry.testSaves;
            if (node.entry.subtreeTriangles >= 0.0f)
                stats->trianglesOccluded += static_cast<std::uint64_t>(std::llround(node.entry.subtreeTriangles));
            h.occludedFrame = frameNumber;
        }
    }
}

void OcclusionTraversal::Impl::testLate(const Entry& entry, std::uint32_t slot) {
    if (!frame->occlusion.coherent)
        return; // late answers are for the next frame's history
    // Spread over frames: each node at its own phase of the interval. After frames without
    // tests, all at once: this frame's history is theirs, and it must see what came to be
    // hidden meanwhile to judge whether testing pays again (judgeFrame()).
    const std::uint32_t interval =
            afterUntested ? 1 : std::max<std::uint32_t>(frame->occlusion.visibleTestInterval, 1);
    const std::size_t phase = NodeKeyHash{}(slots[slot].key) % interval;
    if ((frameNumber + phase) % interval != 0 || !budgetLeft())
        return;
    OcclusionBox box;
    if (!testable(entry, box))
        return;
    lateWaiting.push_back({box, slots[slot].key, entry.testSaves});
}

void OcclusionTraversal::Impl::issueLate() {
    if (lateWaiting.empty())
        return;
    const auto start = std::chrono::steady_clock::now();
    for (const LateTest& test : lateWaiting) {
        if (!budgetLeft())
            break; // the rest keep last frame's answer
        late.push_back({issue({&test.box, 1}), test.key, test.saves});
    }
    lateWaiting.clear();
    stats->occlusionMs += millisecondsSince(start);
}

bool OcclusionTraversal::Impl::enterInstance(
        const storage::NodeRecord& node,
        std::uint32_t parentTransform,
        float priority,
        std::uint32_t& transform,
        storage::NodeRef& rootRef,
        storage::NodeRecord& root) {
    const std::uint32_t instanceIndex = node.geometryPage;
    const storage::InstanceRecord& instance = scene.instances()[instanceIndex];
    const storage::PrototypeRecord& prototype = nodePages.prototypes()[instance.prototype];
    if (nodePages.prototypeRoot(instance.prototype, priority, rootRef, root) != Fetch::Ready) {
        sawCube(node, parentTransform, true); // drawn as its cube (pass 2)
        return false;
    }
    ++stats->instancesEntered;
    const Transform& parent = transforms[parentTransform];
    transform = addTransform(
            parent.matrix * detail::instanceTransform(instance),
            childInstancePath(parent.instancePath, instanceIndex),
            &prototype);
    return true;
}

void OcclusionTraversal::Impl::drawRuns(std::uint32_t transform) {
    const std::uint32_t index = listIndex(transform);
    for (const detail::PayloadRun& run : runs) {
        stats->trianglesDrawn += run.triangles;
        stats->splatsDrawn += run.points;
        list.geometry.push_back(
                {run.page, run.payload, run.first, run.count, index, run.triangles, run.payloadBytes, run.pointPixels});
    }
    if (list.bytes() >= frame->budgets.drawBatchBytes)
        flush();
}

template <typename Child>
OcclusionTraversal::Impl::Expanded OcclusionTraversal::Impl::expandCell(
        const storage::NodeRecord& node,
        std::uint32_t transform,
        float priority,
        Child&& child,
        bool nearestFirst) {
    // A stand-in accurate enough here is drawn instead of the whole subtree (as back to front).
    const Transform& t = transforms[transform];
    const float projected = detail::projectedPixels(node, t.localEye, t.metric, frame->camera, pixelScale);
    detail::Payload drawn = detail::Payload::Own;
    const bool geometryReady =
            nodePages.collectPayload(
                    node,
                    detail::standInView(
                            node,
                            {t.frustum, t.localEye, t.metric},
                            frame->camera,
                            pixelScale,
                            frame->selection,
                            projected),
                    priority,
                    services->uploads,
                    runs,
                    drawn) == Fetch::Ready;
    if (drawn == detail::Payload::Cube) {
        sawCube(node, transform); // pass 2 draws it
        return Expanded::Deferred;
    }
    const bool standIn = drawn != detail::Payload::Own;
    std::span<const std::byte> childPage;
    const bool childrenReady = standIn || node.childCount == 0 ||
                               nodePages.childPage(node, priority, childPage) == Fetch::Ready;
    if (!childrenReady || !geometryReady) {
        sawCube(node, transform, true); // its cube stands in for the subtree (pass 2)
        return Expanded::Deferred;
    }
    if (standIn) {
        ++(drawn == detail::Payload::Splats ? stats->splatSetsDrawn : stats->standInsDrawn);
        drawRuns(transform);
        return Expanded::DrewGeometry;
    }
    // Decode every child before drawing anything, so a bad child leaves the whole cell to its
    // cube, as in the back-to-front walk.
    const std::size_t base = children.size();
    for (std::uint32_t c = 0; c < node.childCount; ++c) {
        const storage::NodeRef childRef = storage::SceneIndex::childRef(node, c);
        float subtreeTriangles = -1.0f;
        Result<storage::NodeRecord> record = nodePages.child(node, childPage, c, &subtreeTriangles);
        if (!record) {
            nodePages.reportFailure(record.status());
            children.resize(base);
            sawCube(node, transform, true);
            return Expanded::Deferred;
        }
        children.push_back({*record, childRef, subtreeTriangles, 0.0f, c});
    }
    if (nearestFirst) {
        for (std::size_t i = base; i < children.size(); ++i) {
            const storage::NodeRecord& r = children[i].record;
            const glm::vec3 centre = 0.5f * (toVec3(r.cellMin) + toVec3(r.cellMax));
            children[i].distance = t.metric.worldLengthSquared(centre - t.localEye);
        }
        std::sort(
                children.begin() + static_cast<std::ptrdiff_t>(base),
                children.end(),
                [](const ChildRecord& a, const ChildRecord& b) {
                    return a.distance != b.distance ? a.distance < b.distance : a.index < b.index;
                });
    }
    const bool drew = !runs.empty();
    if (drew)
        drawRuns(transform);
    for (std::size_t i = base; i < base + node.childCount; ++i) {
        const ChildRecord next = children[i]; // the vector may grow below
        child(next.record, next.ref, next.subtreeTriangles);
    }
    children.resize(base);
    return drew ? Expanded::DrewGeometry : Expanded::NothingOwn;
}

void OcclusionTraversal::Impl::refine(const Entry& entry, std::uint32_t slot, float projected, bool answered) {
    const storage::NodeRecord& node = entry.record;
    const float priority =
            std::min(projected, detail::kTopPriority) * frame->selection.priorityScale;
    if (!detail::isCell(node)) {
        std::uint32_t transform = 0;
        storage::NodeRef rootRef{};
        storage::NodeRecord root{};
        const std::uint64_t untestedBefore = untestedMet;
        if (enterInstance(node, entry.transform, priority, transform, rootRef, root))
            pushChild(root, rootRef, -1.0f, transform, slot, entry.depth + 1); // never tested
        else
            markVisible(slot);
        if (!answered && untestedMet != untestedBefore)
            testLate(entry, slot); // a leaf of the tests (see below)
        return;
    }
    const std::uint64_t untestedBefore = untestedMet;
    const Expanded expanded = expandCell(
            node,
            entry.transform,
            priority,
            [&](const storage::NodeRecord& child, storage::NodeRef ref, float subtreeTriangles) {
                pushChild(child, ref, subtreeTriangles, entry.transform, slot, entry.depth + 1);
            });
    if (expanded != Expanded::NothingOwn)
        markVisible(slot); // its geometry, or its cube, is drawn
    // CHC's leaves, drawn without a test this frame, are tested late to learn whether they went
    // out of sight: the nodes that draw something themselves, and those with a child that is
    // never tested on its own (a cube, a subtree drawn whole) — else a far field that became
    // hidden would stay visible for good. One this frame's test found visible needs none (and
    // would take the frame's test budget from the nodes still waiting for theirs).
    if (!answered && (expanded != Expanded::NothingOwn || node.childCount == 0 || untestedMet != untestedBefore))
        testLate(entry, slot);
}

void OcclusionTraversal::Impl::drawSubtree(
        const storage::NodeRecord& node, std::uint32_t transform, std::uint32_t depth) {
    if (depth > static_cast<std::uint32_t>(detail::kMaxNesting)) {
        reportCycle();
        return;
    }
    float projected = 0.0f;
    const detail::Verdict verdict = classify(node, transforms[transform], projected);
    if (verdict == detail::Verdict::Culled)
        return;
    if (verdict == detail::Verdict::Cube) {
        sawCube(node, transform);
        return;
    }
    const float priority =
            std::min(projected, detail::kTopPriority) * frame->selection.priorityScale;
    if (!detail::isCell(node)) {
        std::uint32_t inner = 0;
        storage::NodeRef rootRef{};
        storage::NodeRecord root{};
        if (enterInstance(node, transform, priority, inner, rootRef, root)) {
            if (depth == wholeWalk.rootDepth && transform == wholeWalk.outer)
                wholeWalk.inner = inner;
            else
                wholeWalk.complete = false; // a frame pass 2 would enter on its own walk
            drawSubtree(root, inner, depth + 1);
        }
        return;
    }
    // Nearest first: the reverse of the back-to-front walk's order, so the cubes met, reversed,
    // are in its order.
    (void)expandCell(
            node,
            transform,
            priority,
            [&](const storage::NodeRecord& child, storage::NodeRef, float) {
                drawSubtree(child, transform, depth + 1);
            },
            true);
}

void OcclusionTraversal::Impl::walkWhole(const Entry& entry, std::uint32_t slot) {
    const auto first = static_cast<std::uint32_t>(metCubes.size());
    // An observer is told of each cube with its node, which only pass 2's own walk has.
    wholeWalk = {frame->selection.observer == nullptr, true, entry.transform, kNone, entry.depth, 0};
    drawSubtree(entry.record, entry.transform, entry.depth);
    if (wholeWalk.recording && wholeWalk.complete) {
        // Pass 2 will not walk it: what it would have counted is counted here. (A record left
        // incomplete is dropped, and pass 2 walks and counts the subtree itself.)
        stats->nodesDeferred += wholeWalk.deferred;
        std::reverse(metCubes.begin() + first, metCubes.end());
        slots[slot].recorded = true;
        slots[slot].walkedFirst = first;
        slots[slot].walkedCount = static_cast<std::uint32_t>(metCubes.size()) - first;
    } else {
        metCubes.resize(first);
    }
    // Nothing below it has a slot: pass 2 walks there, if it does, without asking.
    slots[slot].walked = true;
    wholeWalk.recording = false;
}

const storage::PrototypeRecord* OcclusionTraversal::Impl::prototypeBelow(const Entry& entry) const {
    if (!detail::isCell(entry.record))
        return &nodePages.prototypes()[scene.instances()[entry.record.geometryPage].prototype];
    return transforms[entry.transform].prototype;
}

std::uint64_t OcclusionTraversal::Impl::estimatedTriangles(const Entry& entry) const {
    const storage::PrototypeRecord* prototype = prototypeBelow(entry);
    if (!prototype) // the instance level: its cells hold whole instances
        return std::numeric_limits<std::uint64_t>::max() / 1024;
    if (!detail::isCell(entry.record))
        return prototype->triangleCount;
    // What lies below a node of a prototype's hierarchy, as if its triangles were a surface
    // split evenly four ways a level (a volume splits eight ways: this errs towards testing).
    const unsigned shift = std::min(2u * entry.record.level, 62u);
    const std::uint64_t byLevel = prototype->triangleCount >> shift;
    const glm::vec3 cell = toVec3(entry.record.cellMax) - toVec3(entry.record.cellMin);
    const float edge = std::max({cell.x, cell.y, cell.z});
    if (std::min({cell.x, cell.y, cell.z}) >= edge * (1.0f - 1e-4f))
        return byLevel; // a cubic cell: an octree's (the octree decompositions)
    // A bounding box (D-BVD, p-HBVO, balanced): its levels split two to 33 ways, so the level
    // says little. Its own triangles, or its share of the surface by its box's area, whichever
    // is more: both err towards testing.
    const double whole = boxArea(toVec3(prototype->boundsMin), toVec3(prototype->boundsMax));
    const double share =
            whole > 0.0 ? std::min(1.0, boxArea(toVec3(entry.record.boundsMin), toVec3(entry.record.boundsMax)) / whole)
                        : 1.0;
    const auto byArea = static_cast<std::uint64_t>(share * static_cast<double>(prototype->triangleCount));
    // Format 2's geometryCount counts representations, not triangles (NodePages).
    const std::uint64_t own = nodePages.scene().formatVersion() == storage::kFormatVersion2
                                      ? 0
                                      : static_cast<std::uint64_t>(entry.record.geometryCount);
    return std::max({byLevel, byArea, own});
}

bool OcclusionTraversal::Impl::skipsTests() {
    if (!mayGoUntested())
        untestedFramesLeft = 0; // told since to test every frame
    if (untestedFramesLeft == 0)
        return false;
    const storage::FileHeader& header = scene.header();
    if (!lastCamera || jumped(*lastCamera, frame->camera, toVec3(header.boundsMin), toVec3(header.boundsMax))) {
        untestedFramesLeft = 0; // a new view: what hid too little there says nothing here
        return false;
    }
    lastCamera = frame->camera; // a jump is counted from frame to frame, as when testing
    --untestedFramesLeft;
    return true;
}

Status OcclusionTraversal::Impl::drawUntested() {
    ++stats->occlusionSkipped;
    cubes.setCubesOnly(false);
    const Status drawn = cubes.traverse(*frame, *services, *stats);
    cubes.setCubesOnly(true);
    failures = cubes.newFailures();
    return drawn;
}

void OcclusionTraversal::Impl::judgeFrame() {
    if (!mayGoUntested())
        return;
    // A frame still waiting for pages draws their cubes, which hide nothing: what its tests
    // found says little of what the frame will hide once the pages are in.
    if (stats->nodesDeferred > 0 || stats->pagesMissing > 0)
        return;
    const double drawn = static_cast<double>(stats->trianglesDrawn + stats->cubesDrawn);
    if (hiddenSaves >= static_cast<double>(frame->occlusion.minHiddenShare) * (hiddenSaves + drawn))
        return;
    untestedFramesLeft = kUnpaidFrames;
}

double OcclusionTraversal::Impl::testSaves(const Entry& entry) const {
    double below = static_cast<double>(estimatedTriangles(entry));
    // Seen small, a subtree is cut at ε: at most (size / ε)² cells of it are drawn, each a cube
    // or a leaf's few triangles (its prototype's triangles per node). Not at the instance level,
    // whose cells may stack instances deep (the atoms of a molecule; but see process()).
    if (const storage::PrototypeRecord* prototype = prototypeBelow(entry))
        below = std::min(below, cutTriangles(entry, trianglesPerNode(*prototype)));
    return below;
}

double OcclusionTraversal::Impl::cutTriangles(const Entry& entry, double perNode) const {
    const double epsilon = frame->selection.epsilonPixels;
    if (epsilon <= 0.0)
        return std::numeric_limits<double>::infinity(); // every leaf is drawn
    const double cells = static_cast<double>(entry.projected) / epsilon;
    return cells * cells * perNode;
}

double OcclusionTraversal::Impl::hiddenLikelihood() const {
    if (!withoutHistory || depthDrawn() != evidenceDepth)
        return 1.0; // with history, or something drawn since that a test may be hidden by
    const double hiddenShare = (static_cast<double>(coldHidden) + kPriorAnswers * kPriorHiddenShare) /
                               (static_cast<double>(coldAnswers) + kPriorAnswers);
    return std::min(1.0, hiddenShare / kPriorHiddenShare);
}

void OcclusionTraversal::Impl::reportCycle() {
    nodePages.reportFailure(detail::nestingTooDeep());
}

detail::Verdict OcclusionTraversal::Impl::classify(
        const storage::NodeRecord& node, const Transform& t, float& projected) {
    return detail::classify(
            node,
            {t.frustum, t.localEye, t.metric},
            frame->camera,
            pixelScale,
            frame->selection,
            *stats,
            projected);
}

void OcclusionTraversal::Impl::rememberSlots() {
    for (const Slot& slot : slots) {
        History& h = history[slot.key];
        h.lastSeen = frameNumber;
        if (slot.cubesBelow)
            h.cubesFrame = frameNumber;
        if (slot.walked) {
            h.walkedFrame = frameNumber;
            h.walkedRecorded = slot.recorded;
            h.walkedFirst = slot.walkedFirst;
            h.walkedCount = slot.walkedCount;
        }
        if (slot.visible) {
            h.lastVisible = frameNumber;
            h.hidden = false;
        }
    }
}

void OcclusionTraversal::Impl::finishFrame() {
    if (!late.empty()) {
        services->occlusion->submit();
        for (const LateQuery& query : late) {
            if (services->occlusion->anyVisible(query.ticket))
                continue;
            // Hidden now: tested before it is drawn next frame.
            hiddenSaves += query.saves;
            History& h = history[query.key];
            h.hidden = true;
            h.lastVisible = 0;
            h.hiddenTests = 1;
        }
    }
    if (frameNumber % kHistoryFrames == 0)
        absl::erase_if(history, [&](const auto& item) {
            return item.second.lastSeen + kHistoryFrames < frameNumber;
        });
}

} // namespace ff::runtime
