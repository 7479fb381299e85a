#pragma once

#include <ff/runtime/PageAccess.h>
#include <ff/runtime/Traversal.h>
#include <ff/storage/SceneIndex.h>

#include <cstddef>
#include <memory>
#include <vector>

namespace ff::runtime {

/**
 * Occlusion culling: the ε cut of BackToFrontTraversal, minus what is hidden behind opaque
 * geometry already drawn. Two passes a frame:
 *
 *  1. Front to back (a queue ordered by each node's nearest distance), drawing opaque geometry
 *     and testing node boxes through IOcclusionTester before drawing their subtrees, with the
 *     temporal coherence of CHC++ (Mattausch, Bittner, Wimmer 2008), keyed by NodeKey:
 *     - a node visible last frame is drawn at once, without waiting; a leaf of it is tested
 *       only every OcclusionOptions::visibleTestInterval frames (at its own phase), and that
 *       answer is read at the end of the frame, for the next one;
 *     - a node hidden last frame, or never tested, is queued; queued nodes are tested in
 *       batches after the geometry drawn so far is flushed, those that stayed hidden together
 *       as multiqueries; the walk goes on while the answers are pending and waits only when it
 *       has nothing else to do;
 *     - a node whose box overlaps the box of a nearer node still waiting for its answer is held
 *       back until that answer is in (and what it drew is flushed): tested beside it, it would
 *       not see what it may hide behind — a building's furniture beside its walls, on every
 *       frame without history. On such a frame (the first, a jump) a node is held, too, behind
 *       a box wholly in front of it that covers part of its screen rectangle: the atoms of a
 *       dense volume, layer behind layer, whose boxes never overlap;
 *     - visibility is pulled up from what was drawn: an inner node none of whose subtree was
 *       seen is tested as a whole next frame.
 *     History decides only when a node is tested, never that it is skipped: a node is skipped
 *     only on this frame's answer, so what just became visible is drawn. The first frame (no
 *     history) draws the nearest geometry untested, as the first occluders, and tests the rest.
 *  2. Back to front, the cubes only (translucent: they blend and do not write depth), walked by
 *     a BackToFrontTraversal that skips the nodes pass 1 found hidden: the same cubes in the
 *     same order as without occlusion, minus those behind opaque geometry.
 *
 * With streaming, a node whose pages are not resident is drawn (pass 2) as its cube and tested
 * by its bounds like any other; hidden subtrees are never walked, so their pages are never
 * asked for. Memory: the front-to-back queue holds the frontier of the walk, which grows with
 * the visible cut (unlike BackToFrontTraversal's, which is bounded for any cut); the history
 * keeps the nodes seen in the last 64 frames.
 *
 * Needs TraversalServices::occlusion; --method full is drawn without occlusion. Main thread only.
 */
class OcclusionTraversal final : public ITraversal {
public:
    OcclusionTraversal(const storage::SceneIndex& scene, IPageAccess& pages);
    ~OcclusionTraversal() override;
    OcclusionTraversal(const OcclusionTraversal&) = delete;
    OcclusionTraversal& operator=(const OcclusionTraversal&) = delete;

    [[nodiscard]] Status
    traverse(const FrameContext& frame, TraversalServices services, FrameStats& stats) override;
    [[nodiscard]] const std::vector<Status>& newFailures() const noexcept override;

    /** The last answers: Occluded for nodes hidden at their last test (a prefetch walk skips
     *  them, so what is hidden is not fetched ahead either). */
    [[nodiscard]] const IVisibility& history() const noexcept;

    /**
     * A frame that must be complete is drawn again until it lacks no page, and each pass would
     * enter its answers in the history: a pass without the pages it needs finds nodes visible
     * that are not (nothing drawn yet to hide them), and coherence then keeps drawing them for
     * frames. Between beginRedrawableFrame() and endRedrawableFrame(), the first traverse()
     * keeps the state it started from and redrawLastFrame() makes the next one start from it
     * again, so only the last pass's answers stay.
     */
    void beginRedrawableFrame() noexcept;
    void redrawLastFrame() noexcept;
    void endRedrawableFrame() noexcept;

private:
    struct Impl;
    std::unique_ptr<Impl> mImpl;
};

} // namespace ff::runtime
