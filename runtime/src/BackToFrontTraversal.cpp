// Chamberlain, DeRose, Lischinski, Salesin, Snyder: "Fast Rendering of Complex Environments
// Using a Spatial Hierarchy", GI '96, §3 (the traversal), extended with instancing, with
// streaming (DESIGN.md "Runtime rules": never wait for I/O in a frame) and with bounded batches.

#include <ff/runtime/BackToFrontTraversal.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

namespace ff::runtime {

namespace {

glm::vec3 toVec3(const std::array<float, 3>& a) {
    return {a[0], a[1], a[2]};
}

glm::mat4 instanceTransform(const storage::InstanceRecord& instance) {
    glm::mat4 m(1.0f);
    for (int row = 0; row < 3; ++row)
        for (int col = 0; col < 4; ++col)
            m[col][row] = instance.transform[static_cast<std::size_t>(row * 4 + col)];
    return m;
}

bool isCell(const storage::NodeRecord& node) {
    return node.kind == static_cast<std::uint8_t>(storage::NodeKind::Cell);
}

/** Something finer than the cube exists: children, own triangles or an instance's prototype. */
bool refinable(const storage::NodeRecord& node) {
    return !isCell(node) || node.childCount > 0 || node.geometryCount > 0;
}

/** Largest difference in coverage between two of the cube's axes, each axis the mean alpha of
 *  its two faces (alpha is the byte's linear coverage, 0..1). */
float cubeAnisotropy(const storage::NodeRecord& node) {
    float lo = 1.0f;
    float hi = 0.0f;
    for (int axis = 0; axis < 3; ++axis) {
        const float alpha =
                (static_cast<float>(node.cube[static_cast<std::size_t>(2 * axis)][3]) +
                 static_cast<float>(node.cube[static_cast<std::size_t>(2 * axis + 1)][3])) /
                (2.0f * 255.0f);
        lo = std::min(lo, alpha);
        hi = std::max(hi, alpha);
    }
    return hi - lo;
}

/** SelectionOptions::maxCubeAnisotropy. Anisotropy never exceeds 1, so with the default (1)
 *  nothing is measured. */
bool refusedAsAnisotropic(const storage::NodeRecord& node, float limit) {
    return limit < 1.0f && refinable(node) && cubeAnisotropy(node) > limit;
}

// Priorities for pages nobody can see the size of yet (the root, a full draw).
constexpr float kTopPriority = 1e30f;
/** `--cube-draw auto` draws points up to this ε: every drawn cube then covers at most 4 pixels,
 *  a point at most 2 pixels wide. */
constexpr float kAutoPointsMaxEpsilon = 2.0f;

// Deeper than any builder writes (octree levels <= 20 per prototype, instance level <= 24 plus
// groups): a file nesting further has a reference cycle, which must not overflow the stack.
constexpr int kMaxNesting = 128;

bool drawsCubesAsPoints(const SelectionOptions& options) {
    return options.cubeStyle == CubeStyle::AreaWeightedPoints ||
           (options.cubeStyle == CubeStyle::Auto && options.epsilonPixels <= kAutoPointsMaxEpsilon);
}

template <typename T> std::size_t capacityBytes(const std::vector<T>& v) {
    return v.capacity() * sizeof(T);
}

} // namespace

BackToFrontTraversal::BackToFrontTraversal(const storage::SceneFile& scene, IPageAccess& pages)
    : mScene(scene)
    , mPages(pages)
    , mPrototypeGeometry(scene.prototypes().size())
    , mPrototypeGeometryReady(scene.prototypes().size(), false) {
    // References into the chain stay valid while the walk recurses below them.
    mActive.reserve(kMaxNesting + 2);
}

std::size_t BackToFrontTraversal::scratchBytes() const noexcept {
    std::size_t bytes = capacityBytes(mList.transforms) + capacityBytes(mList.localEyes) +
                        capacityBytes(mList.geometry) + capacityBytes(mList.cubes) +
                        capacityBytes(mActive) + capacityBytes(mChildStack) +
                        capacityBytes(mSegments);
    for (const auto& runs : mPrototypeGeometry)
        bytes += capacityBytes(runs);
    return bytes;
}

Status BackToFrontTraversal::traverse(
        const FrameContext& frame, TraversalServices services, FrameStats& stats) {
    mFrame = &frame;
    mServices = &services;
    mNewFailures.clear();
    mSpilled = false;
    mSinkStatus = Status::ok();
    mPixelScale = frame.camera.pixelScale(static_cast<float>(frame.height));
    const float aspect =
            static_cast<float>(frame.width) / std::max(static_cast<float>(frame.height), 1.0f);
    mViewProjection = frame.camera.projection(aspect) * frame.camera.view();
    FF_RETURN_IF_ERROR(walk(Pass::Everything, stats));
    if (mSpilled) {
        // The cubes again, in the same order, after every geometry batch; counted once already.
        FrameStats counted;
        FF_RETURN_IF_ERROR(walk(Pass::CubesOnly, counted));
    }
    return mSinkStatus;
}

Status BackToFrontTraversal::walk(Pass pass, FrameStats& stats) {
    mPass = pass;
    mStats = &stats;
    mList.clear();
    mActive.clear();
    mChildStack.clear();
    pushActive(glm::mat4(1.0f), 0);
    if (mFrame->selection.method == Method::Full) {
        walkFull();
    } else {
        const storage::NodeRef rootRef = mScene.header().root;
        storage::NodeRecord root{};
        if (readNode(rootRef, kTopPriority, root) == Fetch::Ready)
            visit(root, rootRef, 0, 0);
        else if (!mNewFailures.empty())
            return mNewFailures.front().withContext("the root node is unreadable");
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
    mergeGeometryDraws();
    mList.cubesAsPoints = drawsCubesAsPoints(mFrame->selection);
    if (mSinkStatus.isOk())
        mSinkStatus = mServices->sink.draw(mList, *mStats);
    mList.clear();
    for (ActiveTransform& active : mActive)
        addToList(active);
    return mSinkStatus;
}

void BackToFrontTraversal::reportFailure(const Status& failure) {
    // Corrupt messages start with "page N: ", so equal messages are the same page's failure.
    if (mReported.insert(failure.message()).second)
        mNewFailures.push_back(failure);
}

BackToFrontTraversal::Fetch BackToFrontTraversal::fetch(
        std::uint64_t page,
        storage::PageType type,
        float priority,
        std::span<const std::byte>& payload) {
    const PageLookup lookup = mPages.lookup(page, type, priority);
    if (lookup.availability == PageAvailability::Ready) {
        payload = lookup.payload;
        return Fetch::Ready;
    }
    ++mStats->pagesMissing;
    if (lookup.availability == PageAvailability::Failed && lookup.failure)
        reportFailure(*lookup.failure);
    return Fetch::Missing;
}

BackToFrontTraversal::Fetch
BackToFrontTraversal::readNode(storage::NodeRef ref, float priority, storage::NodeRecord& out) {
    std::span<const std::byte> payload;
    if (fetch(ref.page, storage::PageType::Nodes, priority, payload) != Fetch::Ready)
        return Fetch::Missing;
    Result<storage::NodeRecord> node = mScene.decodeNode(payload, ref);
    if (!node) {
        reportFailure(node.status());
        return Fetch::Missing;
    }
    out = *node;
    return Fetch::Ready;
}

BackToFrontTraversal::Fetch
BackToFrontTraversal::collectGeometry(const storage::NodeRecord& node, float priority) {
    mSegments.clear();
    if (node.geometryCount == 0 || !isCell(node))
        return Fetch::Ready;
    mRuns.clear();
    if (Status status = mScene.geometrySegments(node, mRuns); !status) {
        reportFailure(status);
        return Fetch::Missing;
    }
    // Ask for every page before answering, so all of them are in flight together.
    Fetch result = Fetch::Ready;
    for (const storage::GeometrySegment& s : mRuns) {
        std::span<const std::byte> payload;
        if (fetch(s.page, storage::PageType::Geometry, priority, payload) != Fetch::Ready) {
            result = Fetch::Missing;
        } else if (!mServices->uploads.admit(s.page)) {
            ++mStats->uploadsRefused;
            result = Fetch::Missing;
        } else {
            mSegments.push_back({s, payload.data()});
        }
    }
    return result;
}

void BackToFrontTraversal::defer(
        const storage::NodeRecord& node, storage::NodeRef ref, std::size_t active) {
    ++mStats->nodesDeferred;
    if (node.flags & storage::kNodeHasCube)
        emitCube(node, ref, active);
}

void BackToFrontTraversal::visit(
        const storage::NodeRecord& node, storage::NodeRef ref, std::size_t active, int depth) {
    if (depth > kMaxNesting) {
        reportFailure(
                Status(ErrorCode::Corrupt,
                       "node nesting deeper than " + std::to_string(kMaxNesting) +
                               " levels: the hierarchy has a reference cycle"));
        return;
    }
    ++mStats->nodesVisited;
    const ActiveTransform& frame = mActive[active];
    if (!frame.frustum.intersects(toVec3(node.boundsMin), toVec3(node.boundsMax))) {
        ++mStats->nodesCulled;
        return;
    }
    if (mServices->visibility.visibility({frame.instancePath, ref}) == Visibility::Occluded) {
        ++mStats->nodesOccluded;
        return;
    }

    // ε rule (Chamberlain et al. '96, §3: a cube is drawn where its "projected screen image is no
    // larger than a pixel"): the area the cell's box covers on screen, seen from the eye's
    // direction at the cell's nearest point, below ε² pixels. The area is a box's silhouette
    // (each face's area times |cos| to the eye), the same measure the point shader draws with,
    // and both it and the distance are taken in world units through the whole transform: an
    // instance may scale its axes differently, mirror or shear.
    const SelectionOptions& options = mFrame->selection;
    const glm::vec3 cellMin = toVec3(node.cellMin);
    const glm::vec3 cellMax = toVec3(node.cellMax);
    const glm::vec3& localEye = frame.localEye;
    const TransformMetric& metric = frame.metric;
    const float size =
            std::sqrt(metric.projectedArea(cellMin, cellMax, localEye)); // a square's side
    const float nearest = metric.nearestDistance(cellMin, cellMax, localEye);
    float projected = INFINITY;
    if (mFrame->camera.orthographic)
        projected = size * mPixelScale;
    else if (nearest > 0.0f)
        projected = size * mPixelScale / nearest;
    if (projected < options.epsilonPixels && (node.flags & storage::kNodeHasCube) &&
        !refusedAsAnisotropic(node, options.maxCubeAnisotropy)) {
        emitCube(node, ref, active);
        return;
    }
    const float priority = std::min(projected, kTopPriority) * options.priorityScale;

    if (!isCell(node)) {
        const std::uint32_t instanceIndex = node.geometryPage;
        const storage::InstanceRecord& instance = mScene.instances()[instanceIndex];
        const storage::NodeRef rootRef = mScene.prototypes()[instance.prototype].root;
        storage::NodeRecord root{};
        if (readNode(rootRef, priority, root) != Fetch::Ready) {
            defer(node, ref, active);
            return;
        }
        ++mStats->instancesEntered;
        pushActive(
                frame.matrix * instanceTransform(instance),
                childInstancePath(frame.instancePath, instanceIndex));
        visit(root, rootRef, mActive.size() - 1, depth + 1);
        mActive.pop_back();
        return;
    }

    // Refining needs the cell's own triangles and its children's page; without either, the
    // cell's cube stands in for the whole subtree this frame.
    std::span<const std::byte> childPage;
    const bool childrenReady =
            node.childCount == 0 ||
            fetch(node.firstChild.page, storage::PageType::Nodes, priority, childPage) ==
                    Fetch::Ready;
    const bool geometryReady = collectGeometry(node, priority) == Fetch::Ready;
    if (!childrenReady || !geometryReady) {
        defer(node, ref, active);
        return;
    }
    for (const Segment& s : mSegments)
        emitGeometry(s.segment, s.payload, active);

    // Children farthest first (in world distance), so cubes drawn later blend over what lies
    // behind them.
    const std::size_t base = mChildStack.size();
    for (std::uint32_t c = 0; c < node.childCount; ++c) {
        const storage::NodeRef childRef = storage::SceneFile::childRef(node, c);
        Result<storage::NodeRecord> child = mScene.decodeNode(childPage, childRef);
        if (!child) {
            reportFailure(child.status());
            mChildStack.resize(base);
            defer(node, ref, active);
            return;
        }
        const glm::vec3 d = 0.5f * (toVec3(child->cellMin) + toVec3(child->cellMax)) - localEye;
        mChildStack.push_back({*child, childRef, metric.worldLengthSquared(d)});
    }
    std::sort(
            mChildStack.begin() + static_cast<std::ptrdiff_t>(base),
            mChildStack.end(),
            [](const ChildEntry& a, const ChildEntry& b) { return a.distance > b.distance; });
    for (std::size_t i = base; i < base + node.childCount; ++i) {
        const ChildEntry child = mChildStack[i]; // the stack may grow below
        visit(child.record, child.ref, active, depth + 1);
    }
    mChildStack.resize(base);
}

void BackToFrontTraversal::emitGeometry(
        const storage::GeometrySegment& segment, const std::byte* payload, std::size_t active) {
    mStats->trianglesDrawn += segment.count;
    if (mPass == Pass::CubesOnly)
        return;
    mList.geometry.push_back(
            {segment.page, payload, segment.firstSlot, segment.count, mActive[active].listIndex});
    flushIfFull();
}

// Opaque geometry is depth-tested, so its order is free: sorted by transform and page, runs that
// continue one another become one draw (far fewer draw commands), and both methods submit the
// same triangles in the same order, so ε = 0 reproduces --method full pixel for pixel.
void BackToFrontTraversal::mergeGeometryDraws() {
    auto& draws = mList.geometry;
    std::sort(draws.begin(), draws.end(), [](const GeometryDraw& a, const GeometryDraw& b) {
        if (a.transform != b.transform)
            return a.transform < b.transform;
        return a.page != b.page ? a.page < b.page : a.firstTriangle < b.firstTriangle;
    });
    std::size_t out = 0;
    for (std::size_t i = 0; i < draws.size(); ++i) {
        if (out > 0) {
            GeometryDraw& last = draws[out - 1];
            if (last.transform == draws[i].transform && last.page == draws[i].page &&
                last.firstTriangle + last.triangleCount == draws[i].firstTriangle) {
                last.triangleCount += draws[i].triangleCount;
                continue;
            }
        }
        draws[out++] = draws[i];
    }
    draws.resize(out);
    mStats->geometryDraws += out;
}

void BackToFrontTraversal::emitCube(
        const storage::NodeRecord& node, storage::NodeRef ref, std::size_t active) {
    if (mPass == Pass::CubesOnly) {
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
    // The faces a viewer can see: those whose outer side holds the eye.
    const glm::vec3& eye = mActive[active].localEye;
    std::uint64_t faces = 0;
    for (int axis = 0; axis < 3; ++axis) {
        if (eye[axis] < boxMin[axis] && node.cube[static_cast<std::size_t>(2 * axis)][3] > 0)
            ++faces;
        if (eye[axis] > boxMax[axis] && node.cube[static_cast<std::size_t>(2 * axis + 1)][3] > 0)
            ++faces;
    }
    if (mStats->cubeFacesPerLevel.size() <= node.level)
        mStats->cubeFacesPerLevel.resize(node.level + 1u, 0);
    mStats->cubeFacesPerLevel[node.level] += faces;
    mStats->cubeFacesDrawn += faces;
    if (mPass == Pass::Everything) {
        mList.cubes.push_back({boxMin, boxMax, mActive[active].listIndex, node.cube});
        flushIfFull();
    }
}

// The whole prototype tree, once, merged into per-page runs. Pages that are not Ready yet
// leave the list incomplete and it is rebuilt on a later frame.
void BackToFrontTraversal::collectPrototypeGeometry(std::uint32_t prototype) {
    std::vector<storage::GeometrySegment>& merged = mPrototypeGeometry[prototype];
    merged.clear();
    bool complete = true;
    std::vector<storage::NodeRecord> stack;
    storage::NodeRecord root{};
    if (readNode(mScene.prototypes()[prototype].root, kTopPriority, root) != Fetch::Ready)
        return;
    stack.push_back(root);
    // A prototype has at most the file's nodeCount nodes; more means a reference cycle.
    std::uint64_t budget = mScene.header().nodeCount + 1;
    std::vector<storage::GeometrySegment> runs;
    while (!stack.empty()) {
        if (budget-- == 0) {
            reportFailure(
                    Status(ErrorCode::Corrupt,
                           "prototype " + std::to_string(prototype) +
                                   ": its hierarchy has a reference cycle"));
            break;
        }
        const storage::NodeRecord node = stack.back();
        stack.pop_back();
        runs.clear();
        bool nodeReady = true;
        if (Status status = mScene.geometrySegments(node, runs); !status) {
            reportFailure(status);
            nodeReady = false;
        }
        for (const storage::GeometrySegment& s : runs) {
            std::span<const std::byte> payload;
            if (fetch(s.page, storage::PageType::Geometry, kTopPriority, payload) != Fetch::Ready)
                nodeReady = false;
        }
        if (nodeReady)
            merged.insert(merged.end(), runs.begin(), runs.end());
        else
            complete = false;
        for (std::uint32_t c = 0; c < node.childCount; ++c) {
            storage::NodeRecord child{};
            if (readNode(storage::SceneFile::childRef(node, c), kTopPriority, child) ==
                Fetch::Ready)
                stack.push_back(child);
            else
                complete = false;
        }
    }
    std::sort(merged.begin(), merged.end(), [](const auto& a, const auto& b) {
        return a.page != b.page ? a.page < b.page : a.firstSlot < b.firstSlot;
    });
    runs.clear();
    for (const storage::GeometrySegment& s : merged) {
        if (!runs.empty() && runs.back().page == s.page &&
            runs.back().firstSlot + runs.back().count == s.firstSlot)
            runs.back().count += s.count;
        else
            runs.push_back(s);
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
        pushActive(instanceTransform(instance), childInstancePath(0, i));
        for (const storage::GeometrySegment& s : mPrototypeGeometry[instance.prototype]) {
            std::span<const std::byte> payload;
            if (fetch(s.page, storage::PageType::Geometry, kTopPriority, payload) != Fetch::Ready)
                continue;
            if (!mServices->uploads.admit(s.page)) {
                ++mStats->uploadsRefused;
                continue;
            }
            emitGeometry(s, payload.data(), mActive.size() - 1);
        }
        mActive.pop_back();
    }
}

} // namespace ff::runtime
