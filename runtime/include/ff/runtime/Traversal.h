#pragma once

// Traversal is the CPU half of a frame: it walks the scene's hierarchy for one FrameContext and
// says what to draw. Strategies differ in order and in what they learn from the renderer:
//
//   FrameContext ──► ITraversal ──► IDrawSink (bounded DrawList batches) ──► GL
//                      │   ▲  ▲  ▲
//        IPageAccess ◄─┘   │  │  └─ IOcclusionTester: is this box hidden by what is drawn?
//        (never waits)     │  └──── IUploadGate: may this frame upload that geometry page?
//                          └─────── IVisibility: Unknown | Visible | Occluded, per (instance, node)
//
// BackToFrontTraversal (Chamberlain et al.'s ε walk) asks IVisibility and skips what is
// Occluded. OcclusionTraversal walks front to back, tests boxes through IOcclusionTester, keeps
// state per NodeKey across frames (CHC++-style coherence) and then lets a back-to-front walk
// draw the cubes with what it found Occluded. Traversal stays CPU code: the GL side answers
// through the narrow interfaces below, and every one has a do-nothing or fake implementation
// for tests.

#include <ff/runtime/DrawList.h>
#include <ff/runtime/FrameContext.h>
#include <ff/runtime/FrameStats.h>
#include <ff/storage/SceneFormat.h>
#include <ff/storage/Status.h>

#include <glm/glm.hpp>

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace ff::runtime {

/** What the renderer knows of a node's visibility. Unknown is drawn. */
enum class Visibility : std::uint8_t { Unknown, Visible, Occluded };

/**
 * A node as one instance path sees it: the same prototype node under two instances is two keys.
 * `instancePath` hashes the chain of instance indices from the scene root (0 outside every
 * instance); traversals key state they keep across frames with it.
 */
struct NodeKey {
    std::uint64_t instancePath = 0;
    storage::NodeRef node{};
    friend bool operator==(const NodeKey&, const NodeKey&) = default;
};

struct NodeKeyHash {
    std::size_t operator()(const NodeKey& key) const noexcept {
        // The SplitMix64 finaliser over both halves: every bit of the key reaches every bit of
        // the hash, so std::unordered_map's prime-modulo buckets stay short.
        std::uint64_t z = key.instancePath ^
                          (((std::uint64_t{key.node.page} << 32) | key.node.slot) * 0x9E3779B97F4A7C15ull);
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        return static_cast<std::size_t>(z ^ (z >> 31));
    }
};

/** The instance path below `parent` through instance record `instance`. */
constexpr std::uint64_t childInstancePath(std::uint64_t parent, std::uint32_t instance) noexcept {
    return (parent ^ (std::uint64_t{instance} + 1)) * 0x9E3779B97F4A7C15ull + 0x632BE59BD9B4E019ull;
}

/** A cube an earlier walk of the frame met below a node it walked whole (see IVisibility::Known),
 *  as a cubes-only walk would draw it. */
struct MetCube {
    /** Its transform: 0 the node's own frame, 1 the frame of the instance the node places. */
    CubeDraw draw;
    std::uint8_t facesToward; ///< its faces toward the eye (cube_faces_drawn)
    std::uint8_t level;       ///< its level (cube_faces_per_level)
};

/** What is known of nodes' visibility (this frame's occlusion tests, or the last frame's). */
class IVisibility {
public:
    virtual ~IVisibility() = default;
    /** The answer for `key` (Unknown: never tested). Unknown and Visible are drawn. */
    [[nodiscard]] virtual Visibility visibility(const NodeKey& key) const = 0;

    struct Known {
        Visibility visibility = Visibility::Unknown;
        /** An earlier walk of this frame went through the node's whole subtree: nothing below
         *  it is known (a walk there need not ask). */
        bool walked = false;
        /** And it kept the cubes it met there, `cubes` in back-to-front order: a cubes-only walk
         *  draws them instead of walking the subtree. */
        bool recorded = false;
        std::span<const MetCube> cubes;
    };
    /** The answer for `key` and, where there is one, the earlier walk's (one lookup). */
    [[nodiscard]] virtual Known known(const NodeKey& key) const {
        return {visibility(key), false, false, {}};
    }
};

/** Knows nothing: every node is Unknown (drawn). */
class NoVisibility final : public IVisibility {
public:
    [[nodiscard]] Visibility visibility(const NodeKey&) const override {
        return Visibility::Unknown;
    }
};

/** A box to test, as its eight corners in world space (corner i has bit 0 = x max, bit 1 = y
 *  max, bit 2 = z max in the box's own frame, so a transformed box stays exact), in a
 *  right-handed order: a tester may draw front faces only. */
struct OcclusionBox {
    std::array<glm::vec3, 8> corners;
};

/** A query in flight this frame. */
using QueryTicket = std::uint32_t;

/**
 * Tests boxes against the depth drawn so far this frame (hardware occlusion queries; a depth
 * pyramid). A box is visible when any sample of it would pass the depth test (<=): the answer is
 * conservative, never Occluded for a box something of which can still be seen, since what is
 * drawn later only comes nearer. Answers arrive late; ready() never waits, anyVisible() does.
 * Tickets are valid until the frame ends.
 */
class IOcclusionTester {
public:
    virtual ~IOcclusionTester() = default;
    /** One query over a group of boxes: visible if any of them is (a multiquery). */
    [[nodiscard]] virtual QueryTicket issue(std::span<const OcclusionBox> group) = 0;
    /** Starts the work on what was issued (queries answer only after it is submitted). */
    virtual void submit() = 0;
    [[nodiscard]] virtual bool ready(QueryTicket ticket) = 0;
    /** The answer; waits for it if it is not ready. */
    [[nodiscard]] virtual bool anyVisible(QueryTicket ticket) = 0;
};

/**
 * Receives a frame's draw list batch by batch (the renderer). A batch's payload pointers stay
 * valid until the frame ends. All of a frame's geometry arrives before its first cube, and the
 * cubes arrive in the traversal's back-to-front order: a frame that fits one batch is one batch;
 * one that does not is geometry batches, then cube batches.
 */
class IDrawSink {
public:
    virtual ~IDrawSink() = default;
    [[nodiscard]] virtual Status draw(const DrawList& batch, FrameStats& stats) = 0;
};

/** Draws nothing (prefetch traversals, tests). */
class DiscardingSink final : public IDrawSink {
public:
    [[nodiscard]] Status draw(const DrawList&, FrameStats&) override { return Status::ok(); }
};

/**
 * The GPU's say in which geometry pages a frame may draw: a page not resident on the GPU costs
 * an upload, and uploads per frame are bounded (FrameBudgets::gpuUploadsPerFrame). A refused
 * page is treated like one still on disk: its cell is drawn as its cube this frame. Answers are
 * stable within a frame (asking twice gives the same answer).
 */
class IUploadGate {
public:
    virtual ~IUploadGate() = default;
    [[nodiscard]] virtual bool admit(std::uint64_t geometryPage) = 0;
};

/** Admits every page (the synchronous reference, prefetch, tests). */
class AdmitAll final : public IUploadGate {
public:
    [[nodiscard]] bool admit(std::uint64_t) override { return true; }
};

/** What a traversal talks to besides the pages. Borrowed for one traverse() call. */
struct TraversalServices {
    IDrawSink& sink;
    const IVisibility& visibility;
    IUploadGate& uploads;
    /** Occlusion tests (OcclusionTraversal needs one; the others ignore it). */
    IOcclusionTester* occlusion = nullptr;
};

/** A strategy for walking the scene once per frame. Main thread only. */
class ITraversal {
public:
    virtual ~ITraversal() = default;
    /** Hands the frame's draw list to `services.sink` in batches and fills the selection
     *  counters of `stats`. Errors only for what leaves nothing to draw (the root page failed)
     *  and for what the sink reports. */
    [[nodiscard]] virtual Status
    traverse(const FrameContext& frame, TraversalServices services, FrameStats& stats) = 0;
    /** Page failures first met during the last traverse() (each is reported once). */
    [[nodiscard]] virtual const std::vector<Status>& newFailures() const noexcept = 0;
};

} // namespace ff::runtime
