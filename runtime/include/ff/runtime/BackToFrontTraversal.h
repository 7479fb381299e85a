#pragma once

#include <ff/runtime/Frustum.h>
#include <ff/runtime/PageAccess.h>
#include <ff/runtime/TransformMetric.h>
#include <ff/runtime/Traversal.h>
#include <ff/storage/SceneIndex.h>

#include <cstdint>
#include <memory>
#include <vector>

namespace ff::runtime::detail {
class NodePages;
struct PayloadRun;
} // namespace ff::runtime::detail

namespace ff::runtime {

/**
 * The back-to-front ε traversal (Chamberlain et al. '96, §3): walks the scene from the
 * instance-level root, skipping cells outside the frustum or Occluded, drawing a cell as its
 * color cube when its box covers less than ε² pixels, a cell's own triangles when it is refined
 * (each triangle once), and children in back-to-front order. Instances enter their prototype's
 * hierarchy with the instance transform.
 *
 * Pages come through an IPageAccess and it never waits for one: a cell whose children or
 * triangles are not Ready (or whose geometry the upload gate refuses) is drawn as its own cube
 * instead (counted as debt in the stats) and the missing pages are asked for, larger projected
 * size first. A failed page leaves its subtree drawn with the nearest resident ancestor's cube
 * and is reported once.
 *
 * Bounded memory: the draw list goes to the sink in batches of FrameBudgets::drawBatchBytes and
 * the walk keeps only the chain of instances it is inside, so a frame's transient memory is the
 * same for a cut of 10^3 or 10^8 nodes. A frame that spills over one batch is walked twice: once
 * for its geometry (order-free, depth-tested), then again for its cubes, which keeps the cubes'
 * global back-to-front order after all the geometry, exactly as one batch would draw them.
 *
 * Main thread only. Scratch memory is reused between frames.
 */
class BackToFrontTraversal final : public ITraversal {
public:
    BackToFrontTraversal(const storage::SceneIndex& scene, IPageAccess& pages);
    ~BackToFrontTraversal() override;

    [[nodiscard]] Status
    traverse(const FrameContext& frame, TraversalServices services, FrameStats& stats) override;
    [[nodiscard]] const std::vector<Status>& newFailures() const noexcept override;

    /** Draws only the frame's cubes, in the same back-to-front order (and counts them); its
     *  geometry was drawn by another traversal that told IVisibility what it found Occluded
     *  (OcclusionTraversal's second pass). */
    void setCubesOnly(bool cubesOnly) noexcept { mCubesOnly = cubesOnly; }

    /** Bytes the walk's own scratch holds now (its batch, stacks and per-prototype runs). */
    [[nodiscard]] std::size_t scratchBytes() const noexcept;

private:
    /** An instance the walk is inside: its transform, where it is in the batch being filled,
     *  and what the ε rule and the frustum test need in its local frame. */
    struct ActiveTransform {
        glm::mat4 matrix;
        glm::vec3 localEye;
        TransformMetric metric;
        Frustum frustum;
        std::uint64_t instancePath;
        std::uint32_t listIndex; ///< its index in mList.transforms
    };
    struct ChildEntry {
        storage::NodeRecord record;
        storage::NodeRef ref;
        float distance;
        std::uint32_t index; ///< among its siblings: ties in distance go by it
    };
    /** What the pass in progress emits (see the class comment). */
    enum class Pass { Everything, GeometryOnly, CubesOnly };

    Status walk(Pass pass, FrameStats& stats);
    /** `ask`: whether the visibility may know anything of the node (not below a node an
     *  earlier walk went through whole). */
    void visit(
            const storage::NodeRecord& node,
            storage::NodeRef ref,
            std::size_t active,
            int depth,
            bool ask = true);
    void emitGeometry(const detail::PayloadRun& run, std::size_t active);
    void emitCube(const storage::NodeRecord& node, storage::NodeRef ref, std::size_t active);
    void defer(const storage::NodeRecord& node, storage::NodeRef ref, std::size_t active);
    /** Draws the cubes an earlier walk met below `node` (IVisibility::Known) instead of walking
     *  there again. */
    void drawMetCubes(
            const storage::NodeRecord& node, std::span<const MetCube> cubes, std::size_t active);
    void pushActive(const glm::mat4& transform, std::uint64_t instancePath);
    void addToList(ActiveTransform& active);
    /** Hands a full batch to the sink and starts the next one. */
    void flushIfFull();
    Status flush();
    void walkFull();
    void collectPrototypeGeometry(std::uint32_t prototype);

    const storage::SceneIndex& mScene;
    std::unique_ptr<detail::NodePages> mNodePages;
    bool mCubesOnly = false;
    // Per-frame state.
    const FrameContext* mFrame = nullptr;
    TraversalServices* mServices = nullptr;
    FrameStats* mStats = nullptr;
    Pass mPass = Pass::Everything;
    bool mSpilled = false; ///< the Everything pass overflowed its batch: cubes need their own pass
    Status mSinkStatus;    ///< the first error the sink reported this frame
    float mPixelScale = 1.0f;
    glm::mat4 mViewProjection{1.0f};
    DrawList mList;
    std::vector<ActiveTransform> mActive; ///< the chain of instances being walked, root first
    std::vector<ChildEntry> mChildStack;
    std::vector<detail::PayloadRun> mRuns; ///< a cell's own geometry runs
    /** Full method: every geometry run of each prototype, merged per page (built on demand). */
    std::vector<std::vector<detail::PayloadRun>> mPrototypeGeometry;
    std::vector<bool> mPrototypeGeometryReady;
};

} // namespace ff::runtime
