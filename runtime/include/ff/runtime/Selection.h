#pragma once

#include <ff/runtime/Camera.h>
#include <ff/runtime/DrawList.h>
#include <ff/runtime/FrameStats.h>
#include <ff/runtime/Frustum.h>
#include <ff/storage/SceneFile.h>
#include <ff/storage/Status.h>

#include <cstdint>
#include <vector>

namespace ff::runtime {

enum class Method {
    Hierarchical, ///< Chamberlain's traversal: frustum culling, ε rule, cubes back to front
    Full,         ///< every triangle of every instance, no hierarchy (the brute-force baseline)
};

struct SelectionOptions {
    Method method = Method::Hierarchical;
    /** A cell whose projected size is below this many pixels is drawn as its color cube;
     *  0 draws geometry everywhere. */
    float epsilonPixels = 1.0f;
    float viewportWidth = 640.0f;
    float viewportHeight = 480.0f;
};

/**
 * Per-frame selection (Chamberlain et al. '96, §3): walks the scene from the instance-level
 * root, skipping cells outside the frustum, drawing a cell as its color cube when it projects
 * smaller than ε pixels, a cell's own triangles when it is refined (each triangle once), and
 * children in back-to-front order. Instances enter their prototype's hierarchy with the
 * instance transform. CPU only: no GL here.
 *
 * Main thread only. Scratch memory is reused between frames.
 */
class Selection {
public:
    explicit Selection(const storage::SceneFile& scene);

    /** Fills `out` (cleared first) and the selection counters of `stats`.
     *  Errors: Corrupt (naming the page) when a node or page fails its checks. */
    [[nodiscard]] Status select(const Camera& camera, const SelectionOptions& options, DrawList& out, FrameStats& stats);

private:
    struct ChildEntry {
        storage::NodeRecord record;
        float distance;
    };

    Status visit(const storage::NodeRecord& node, std::uint32_t transform);
    Status emitGeometry(const storage::NodeRecord& node, std::uint32_t transform);
    void emitCube(const storage::NodeRecord& node, std::uint32_t transform);
    std::uint32_t pushTransform(const glm::mat4& transform);
    Status selectFull();
    void mergeGeometryDraws();
    Status collectPrototypeGeometry(std::uint32_t prototype);

    const storage::SceneFile& mScene;
    // Per-frame state.
    const Camera* mCamera = nullptr;
    SelectionOptions mOptions;
    DrawList* mOut = nullptr;
    FrameStats* mStats = nullptr;
    float mPixelScale = 1.0f;
    std::vector<float> mTransformScale; ///< largest axis scale of each transform
    std::vector<Frustum> mFrusta; ///< per transform: the frustum in that local frame
    std::vector<ChildEntry> mChildStack;
    std::vector<storage::GeometrySegment> mSegments;
    /** Full method: every geometry run of each prototype, merged per page (built on demand). */
    std::vector<std::vector<storage::GeometrySegment>> mPrototypeGeometry;
    std::vector<bool> mPrototypeGeometryReady;
};

} // namespace ff::runtime
