// Chamberlain, DeRose, Lischinski, Salesin, Snyder: "Fast Rendering of Complex Environments
// Using a Spatial Hierarchy", GI '96, §3 (the traversal), extended with instancing, with
// streaming (DESIGN.md "Runtime rules": never wait for I/O in a frame) and with bounded batches.

#include <ff/runtime/BackToFrontTraversal.h>

#include "NodePages.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

namespace ff::runtime {

namespace {

using detail::Fetch;
using detail::kMaxNesting;
using detail::kTopPriority;
using detail::toVec3;

template <typename T> std::size_t capacityBytes(const std::vector<T>& v) {
    return v.capacity() * sizeof(T);
}

} // namespace

BackToFrontTraversal::BackToFrontTraversal(const storage::SceneIndex& scene, IPageAccess& pages)
    : mScene(scene)
    , mNodePages(std::make_unique<detail::NodePages>(scene, pages))
    , mPrototypeGeometry(scene.prototypeCount())
    , mPrototypeGeometryReady(scene.prototypeCount(), false) {
    // References into the chain stay valid while the walk recurses below them.
    mActive.reserve(kMaxNesting + 2);
}

BackToFrontTraversal::~BackToFrontTraversal() = default;

const std::vector<Status>& BackToFrontTraversal::newFailures() const noexcept {
    return mNodePages->newFailures();
}

std::size_t BackToFrontTraversal::scratchBytes() const noexcept {
    std::size_t bytes = capacityBytes(mList.transforms) + capacityBytes(mList.localEyes) +
                        capacityBytes(mList.geometry) + capacityBytes(mList.cubes) +
                        capacityBytes(mActive) + capacityBytes(mChildStack) +
                        capacityBytes(mRuns);
    for (const auto& runs : mPrototypeGeometry)
        bytes += capacityBytes(runs);
    return bytes;
}

Status BackToFrontTraversal::traverse(
        const FrameContext& frame, TraversalServices services, FrameStats& stats) {
    mFrame = &frame;
    mServices = &services;
    mNodePages->beginFrame();
    mSpilled = false;
    mSinkStatus = Status::ok();
    mPixelScale = frame.camera.pixelScale(static_cast<float>(frame.height));
    const float aspect =
            static_cast<float>(frame.width) / std::max(static_cast<float>(frame.height), 1.0f);
    mViewProjection = frame.camera.projection(aspect) * frame.camera.view();
    FF_RETURN_IF_ERROR(walk(mCubesOnly ? Pass::CubesOnly : Pass::Everything, stats));
    if (mSpilled) {
        // The cubes again, in the same order, after every geometry batch; counted once already,
        // but their batches' drawing is this frame's draw time.
        FrameStats counted;
        FF_RETURN_IF_ERROR(walk(Pass::CubesOnly, counted));
        stats.drawMs += counted.drawMs;
    }
    return mSinkStatus;
}

Status BackToFrontTraversal::walk(Pass pass, FrameStats& stats) {
    mPass = pass;
    mStats = &stats;
    mNodePages->countInto(stats);
    mList.clear();
    mActive.clear();
    mChildStack.clear();
    pushActive(glm::mat4(1.0f), 0);
    if (mFrame->selection.method == Method::Full) {
        walkFull();
    } else {
        storage::NodeRef rootRef{};
        storage::NodeRecord root{};
        if (mNodePages->root(kTopPriority, rootRef, root) == Fetch::Ready)
            visit(root, rootRef, 0, 0);
        else if (!mNodePages->newFailures().empty())
            return mNodePages->newFailures().front().withContext("the root node is unreadable");
    }
    return flush();
}

void BackToFrontTraversal::addToList(ActiveTransform& active) {
    active.listIndex = static_cast<std::uint32_t>(mList.transforms.size());
    mList.transforms.push_back(active.matrix);
    mList.localEyes.push_back(active.localEye);
}

void BackToFrontTraversal::pushActive(const glm::mat4& transform, std::uint64_t instancePath) {
    const glm::vec3 localEye =
            glm::vec3(glm::inverse(transform) * glm::vec4(mFrame->camera.eye, 1.0f));
    mActive.push_back(
            {transform,
             localEye,
             TransformMetric(transform),
             Frustum(mViewProjection * transform),
             instancePath,
             0});
    addToList(mActive.back());
    flushIfFull();
}

void BackToFrontTraversal::flushIfFull() {
    if (mList.bytes() < mFrame->budgets.drawBatchBytes)
        return;
    if (mPass == Pass::Everything) {
        // Geometry must all be drawn before the first cube blends over it: from here on this
        // pass draws geometry only, and a second pass draws every cube.
        mSpilled = true;
        mPass = Pass::GeometryOnly;
        mList.cubes.clear();
    }
    (void)flush();
}

Status BackToFrontTraversal::flush() {
    mStats->geometryDraws += detail::mergeGeometryDraws(mList.geometry);
    mList.cubesAsPoints = detail::drawsCubesAsPoints(mFrame->selection);
    mList.splats = mFrame->selection.splats;
    if (mSinkStatus.isOk())
        mSinkStatus = mServices->sink.draw(mList, *mStats);
    mList.clear();
    for (ActiveTransform& active : mActive)
        addToList(active);
    return mSinkStatus;
}

void BackToFrontTraversal::defer(
        const storage::NodeRecord& node, storage::NodeRef ref, std::size_t active) {
    ++mStats->nodesDeferred;
    if (node.flags & storage::kNodeHasCube)
        emitCube(node, ref, active);
}

void BackToFrontTraversal::visit(
        const storage::NodeRecord& node,
        storage::NodeRef ref,
        std::size_t active,
        int depth,
        bool ask) {
    if (depth > kMaxNesting) {
        mNodePages->reportFailure(detail::nestingTooDeep());
        return;
    }
    const ActiveTransform& frame = mActive[active];
    const SelectionOptions& options = mFrame->selection;
    float projected = 0.0f;
    const detail::Verdict verdict = detail::classify(
            node,
            {frame.frustum, frame.localEye, frame.metric},
            mFrame->camera,
            mPixelScale,
            options,
            *mStats,
            projected);
    if (verdict == detail::Verdict::Culled)
        return;
    if (verdict == detail::Verdict::Cube) {
        emitCube(node, ref, active);
        return;
    }
    // A cube costs less to draw than to ask about; what is refined is skipped if Occluded.
    // Below a node an earlier walk went through whole nothing is known, and nothing is asked:
    // at the forest's edge 677 k of pass 2's 825 k lookups were there, every one a miss.
    const IVisibility::Known known =
            ask ? mServices->visibility.known({frame.instancePath, ref}) : IVisibility::Known{};
    if (known.visibility == Visibility::Occluded) {
        ++mStats->nodesOccluded;
        return;
    }
    if (known.recorded && mPass == Pass::CubesOnly && mCubesOnly) {
        drawMetCubes(node, known.cubes, active);
        return;
    }
    const float priority = std::min(projected, kTopPriority) * options.priorityScale;

    if (!detail::isCell(node)) {
        const std::uint32_t instanceIndex = node.geometryPage;
        const storage::InstanceRecord& instance = mScene.instances()[instanceIndex];
        storage::NodeRef rootRef{};
        storage::NodeRecord root{};
        if (mNodePages->prototypeRoot(instance.prototype, priority, rootRef, root) != Fetch::Ready) {
            defer(node, ref, active);
            return;
        }
        ++mStats->instancesEntered;
        pushActive(
                frame.matrix * detail::instanceTransform(instance),
                childInstancePath(frame.instancePath, instanceIndex));
        visit(root, rootRef, mActive.size() - 1, depth + 1, ask && !known.walked);
        mActive.pop_back();
        return;
    }

    // A stand-in accurate enough here is drawn instead of the whole subtree. Else refining
    // needs the cell's own triangles and its children's page; without either, the cell's cube
    // stands in for the whole subtree this frame.
    detail::Payload drawn = detail::Payload::Own;
    const bool geometryReady =
            mNodePages->collectPayload(
                    node,
                    detail::standInView(
                            node,
                            {frame.frustum, frame.localEye, frame.metric},
                            mFrame->camera,
                            mPixelScale,
                            options,
                            projected),
                    priority,
                    mServices->uploads,
                    mRuns,
                    drawn) == Fetch::Ready;
    if (drawn == detail::Payload::Cube) {
        emitCube(node, ref, active);
        return;
    }
    const bool standIn = drawn != detail::Payload::Own;
    std::span<const std::byte> childPage;
    const bool childrenReady =
            standIn || node.childCount == 0 ||
            mNodePages->childPage(node, priority, childPage) == Fetch::Ready;
    if (!childrenReady || !geometryReady) {
        defer(node, ref, active);
        return;
    }
    if (standIn) {
        ++(drawn == detail::Payload::Splats ? mStats->splatSetsDrawn : mStats->standInsDrawn);
        for (const detail::PayloadRun& run : mRuns)
            emitGeometry(run, active);
        return;
    }
    for (const detail::PayloadRun& run : mRuns)
        emitGeometry(run, active);

    // Children farthest first (in world distance), so cubes drawn later blend over what lies
    // behind them.
    const std::size_t base = mChildStack.size();
    for (std::uint32_t c = 0; c < node.childCount; ++c) {
        const storage::NodeRef childRef = storage::SceneIndex::childRef(node, c);
        Result<storage::NodeRecord> child = mNodePages->child(node, childPage, c);
        if (!child) {
            mNodePages->reportFailure(child.status());
            mChildStack.resize(base);
            defer(node, ref, active);
            return;
        }
        const glm::vec3 d =
                0.5f * (toVec3(child->cellMin) + toVec3(child->cellMax)) - frame.localEye;
        mChildStack.push_back({*child, childRef, frame.metric.worldLengthSquared(d), c});
    }
    // Ties go by the sibling index, reversed, so this order is exactly the reverse of
    // OcclusionTraversal's nearest-first walk of a subtree (whose cubes it may take as met).
    std::sort(
            mChildStack.begin() + static_cast<std::ptrdiff_t>(base),
            mChildStack.end(),
            [](const ChildEntry& a, const ChildEntry& b) {
                return a.distance != b.distance ? a.distance > b.distance : a.index > b.index;
            });
    for (std::size_t i = base; i < base + node.childCount; ++i) {
        const ChildEntry child = mChildStack[i]; // the stack may grow below
        visit(child.record, child.ref, active, depth + 1, ask && !known.walked);
    }
    mChildStack.resize(base);
}

void BackToFrontTraversal::drawMetCubes(
        const storage::NodeRecord& node, std::span<const MetCube> cubes, std::size_t active) {
    // A cube in the frame of the instance the node places (`draw.transform` 1) needs that
    // frame in the batch, as entering the instance would have added it.
    std::size_t inner = active;
    for (const MetCube& met : cubes) {
        if (met.draw.transform == 1 && inner == active) {
            const storage::InstanceRecord& instance = mScene.instances()[node.geometryPage];
            const glm::mat4 matrix = mActive[active].matrix * detail::instanceTransform(instance);
            pushActive(matrix, childInstancePath(mActive[active].instancePath, node.geometryPage));
            inner = mActive.size() - 1;
        }
        ++mStats->cubesDrawn;
        if (mStats->cubeFacesPerLevel.size() <= met.level)
            mStats->cubeFacesPerLevel.resize(met.level + 1u, 0);
        mStats->cubeFacesPerLevel[met.level] += met.facesToward;
        mStats->cubeFacesDrawn += met.facesToward;
        mList.cubes.push_back(met.draw);
        mList.cubes.back().transform = mActive[met.draw.transform == 1 ? inner : active].listIndex;
        flushIfFull();
    }
    if (inner != active)
        mActive.pop_back();
}

void BackToFrontTraversal::emitGeometry(const detail::PayloadRun& run, std::size_t active) {
    mStats->trianglesDrawn += run.triangles;
    mStats->splatsDrawn += run.points;
    if (mPass == Pass::CubesOnly)
        return;
    mList.geometry.push_back(
            {run.page,
             run.payload,
             run.first,
             run.count,
             mActive[active].listIndex,
             run.triangles,
             run.payloadBytes,
             run.pointPixels});
    flushIfFull();
}

void BackToFrontTraversal::emitCube(
        const storage::NodeRecord& node, storage::NodeRef ref, std::size_t active) {
    if (mPass == Pass::CubesOnly && !mCubesOnly) {
        // Counted (and reported to the observer) by the first pass.
        mList.cubes.push_back(
                {toVec3(node.cellMin), toVec3(node.cellMax), mActive[active].listIndex, node.cube});
        flushIfFull();
        return;
    }
    if (mFrame->selection.observer)
        mFrame->selection.observer->cubeDrawn(ref, node);
    const glm::vec3 boxMin = toVec3(node.cellMin);
    const glm::vec3 boxMax = toVec3(node.cellMax);
    ++mStats->cubesDrawn;
    const std::uint64_t faces = detail::cubeFacesToward(node, mActive[active].localEye, 1);
    if (mStats->cubeFacesPerLevel.size() <= node.level)
        mStats->cubeFacesPerLevel.resize(node.level + 1u, 0);
    mStats->cubeFacesPerLevel[node.level] += faces;
    mStats->cubeFacesDrawn += faces;
    if (mPass == Pass::Everything || mPass == Pass::CubesOnly) {
        mList.cubes.push_back({boxMin, boxMax, mActive[active].listIndex, node.cube});
        flushIfFull();
    }
}

// The whole prototype tree, once, merged into per-page runs. Pages that are not Ready yet
// leave the list incomplete and it is rebuilt on a later frame.
void BackToFrontTraversal::collectPrototypeGeometry(std::uint32_t prototype) {
    std::vector<detail::PayloadRun>& merged = mPrototypeGeometry[prototype];
    merged.clear();
    bool complete = true;
    std::vector<storage::NodeRecord> stack;
    storage::NodeRef rootRef{};
    storage::NodeRecord root{};
    if (mNodePages->prototypeRoot(prototype, kTopPriority, rootRef, root) != Fetch::Ready)
        return;
    stack.push_back(root);
    // A prototype has at most the file's nodeCount nodes; more means a reference cycle.
    std::uint64_t budget = mScene.header().nodeCount + 1;
    std::vector<detail::PayloadRun> runs;
    while (!stack.empty()) {
        if (budget-- == 0) {
            mNodePages->reportFailure(
                    Status(ErrorCode::Corrupt,
                           "prototype " + std::to_string(prototype) +
                                   ": its hierarchy has a reference cycle"));
            break;
        }
        const storage::NodeRecord node = stack.back();
        stack.pop_back();
        runs.clear();
        if (mNodePages->payloadRuns(node, kTopPriority, runs) == Fetch::Ready)
            merged.insert(merged.end(), runs.begin(), runs.end());
        else
            complete = false;
        std::span<const std::byte> childPage;
        if (node.childCount > 0 &&
            mNodePages->childPage(node, kTopPriority, childPage) != Fetch::Ready) {
            complete = false;
            continue;
        }
        for (std::uint32_t c = 0; c < node.childCount; ++c) {
            Result<storage::NodeRecord> child = mNodePages->child(node, childPage, c);
            if (child) {
                stack.push_back(*child);
            } else {
                mNodePages->reportFailure(child.status());
                complete = false;
            }
        }
    }
    // Only where runs lie is kept: the pages' bytes are looked up again each frame.
    std::sort(merged.begin(), merged.end(), [](const auto& a, const auto& b) {
        return a.page != b.page ? a.page < b.page : a.first < b.first;
    });
    runs.clear();
    for (const detail::PayloadRun& r : merged) {
        if (!runs.empty() && runs.back().page == r.page &&
            runs.back().first + runs.back().count == r.first) {
            runs.back().count += r.count;
            runs.back().triangles += r.triangles;
        } else {
            runs.push_back(r);
        }
    }
    merged = std::move(runs);
    mPrototypeGeometryReady[prototype] = complete;
}

void BackToFrontTraversal::walkFull() {
    const auto& instances = mScene.instances();
    for (std::uint32_t i = 0; i < instances.size(); ++i) {
        const storage::InstanceRecord& instance = instances[i];
        if (!mPrototypeGeometryReady[instance.prototype])
            collectPrototypeGeometry(instance.prototype);
        pushActive(detail::instanceTransform(instance), childInstancePath(0, i));
        for (detail::PayloadRun run : mPrototypeGeometry[instance.prototype]) {
            std::span<const std::byte> payload;
            if (mNodePages->fetch(run.page, storage::PageType::Geometry, kTopPriority, payload) != Fetch::Ready)
                continue;
            if (!mServices->uploads.admit(run.page)) {
                ++mStats->uploadsRefused;
                continue;
            }
            run.payload = payload.data();
            run.payloadBytes = static_cast<std::uint32_t>(payload.size());
            emitGeometry(run, mActive.size() - 1);
        }
        mActive.pop_back();
    }
}

} // namespace ff::runtime
