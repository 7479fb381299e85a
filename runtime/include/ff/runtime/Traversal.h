#pragma once

// Traversal is the CPU half of a frame: it walks the scene's hierarchy for one FrameContext and
// says what to draw. Strategies differ in order and in what they learn from the renderer:
//
//   FrameContext ──► ITraversal ──► IDrawSink (bounded DrawList batches) ──► GL
//                      │   ▲  ▲
//        IPageAccess ◄─┘   │  └─ IUploadGate: may this frame upload that geometry page?
//        (never waits)     └──── IVisibility: Unknown | Visible | Occluded, per (instance, node)
//
// BackToFrontTraversal (Chamberlain et al.'s ε walk) is today's strategy; it asks IVisibility
// and skips what is Occluded, so a renderer that answers makes it cull. A front-to-back walk
// that queries visibility itself and keeps state per NodeKey across frames (CHC++-style, issue
// 15) implements the same interface. Traversal stays CPU code: the GL side answers through the
// three narrow interfaces below, and every one has a do-nothing implementation for tests.

#include <ff/runtime/DrawList.h>
#include <ff/runtime/FrameContext.h>
#include <ff/runtime/FrameStats.h>
#include <ff/storage/SceneFormat.h>
#include <ff/storage/Status.h>

#include <glm/glm.hpp>

#include <cstdint>
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

/** The instance path below `parent` through instance record `instance`. */
constexpr std::uint64_t childInstancePath(std::uint64_t parent, std::uint32_t instance) noexcept {
    return (parent ^ (std::uint64_t{instance} + 1)) * 0x9E3779B97F4A7C15ull + 0x632BE59BD9B4E019ull;
}

/**
 * The renderer's answers about visibility (hardware occlusion queries, a depth pyramid read
 * back, ...). Answers arrive late: what a query issued in frame N says is read in frame N + k.
 */
class IVisibility {
public:
    virtual ~IVisibility() = default;
    /** The latest answer for `key`'s box (Unknown: never tested, or not answered yet). */
    [[nodiscard]] virtual Visibility visibility(const NodeKey& key) const = 0;
    /** Asks for `key`'s box (in the frame of `batch.transforms[transform]` of the batch now
     *  being filled) to be tested against what is drawn this frame. */
    virtual void
    test(const NodeKey& key,
         const glm::vec3& boxMin,
         const glm::vec3& boxMax,
         std::uint32_t transform) = 0;
};

/** Knows nothing: every node is Unknown (drawn), tests are dropped. */
class NoVisibility final : public IVisibility {
public:
    [[nodiscard]] Visibility visibility(const NodeKey&) const override {
        return Visibility::Unknown;
    }
    void test(const NodeKey&, const glm::vec3&, const glm::vec3&, std::uint32_t) override {}
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
    IVisibility& visibility;
    IUploadGate& uploads;
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
