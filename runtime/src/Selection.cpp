#include <ff/runtime/Selection.h>

#include <algorithm>
#include <cmath>

namespace ff::runtime {

namespace {

glm::vec3 toVec3(const std::array<float, 3>& a) { return {a[0], a[1], a[2]}; }

glm::mat4 instanceTransform(const storage::InstanceRecord& instance) {
    glm::mat4 m(1.0f);
    for (int row = 0; row < 3; ++row)
        for (int col = 0; col < 4; ++col)
            m[col][row] = instance.transform[static_cast<std::size_t>(row * 4 + col)];
    return m;
}

} // namespace

Selection::Selection(const storage::SceneFile& scene)
    : mScene(scene)
    , mPrototypeGeometry(scene.prototypes().size())
    , mPrototypeGeometryReady(scene.prototypes().size(), false) {}

std::uint32_t Selection::pushTransform(const glm::mat4& transform) {
    const auto index = static_cast<std::uint32_t>(mOut->transforms.size());
    mOut->transforms.push_back(transform);
    mOut->localEyes.push_back(glm::vec3(glm::inverse(transform) * glm::vec4(mCamera->eye, 1.0f)));
    mTransformScale.push_back(std::max({glm::length(glm::vec3(transform[0])), glm::length(glm::vec3(transform[1])),
                                        glm::length(glm::vec3(transform[2]))}));
    const float aspect = mOptions.viewportWidth / std::max(mOptions.viewportHeight, 1.0f);
    mFrusta.emplace_back(mCamera->projection(aspect) * mCamera->view() * transform);
    return index;
}

Status Selection::select(const Camera& camera, const SelectionOptions& options, DrawList& out, FrameStats& stats) {
    mCamera = &camera;
    mOptions = options;
    mOut = &out;
    mStats = &stats;
    mPixelScale = camera.pixelScale(options.viewportHeight);
    out.clear();
    mTransformScale.clear();
    mFrusta.clear();
    mChildStack.clear();
    pushTransform(glm::mat4(1.0f));
    if (options.method == Method::Full) {
        FF_RETURN_IF_ERROR(selectFull());
    } else {
        FF_ASSIGN_OR_RETURN(const storage::NodeRecord root, mScene.node(mScene.header().root));
        FF_RETURN_IF_ERROR(visit(root, 0));
    }
    mergeGeometryDraws();
    return Status::ok();
}

// Opaque geometry is depth-tested, so its order is free: sorted by transform and page, runs that
// continue one another become one draw (far fewer draw commands), and both methods submit the
// same triangles in the same order, so ε = 0 reproduces --method full pixel for pixel.
void Selection::mergeGeometryDraws() {
    auto& draws = mOut->geometry;
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
    mStats->geometryDraws = out;
}

Status Selection::visit(const storage::NodeRecord& node, std::uint32_t transform) {
    ++mStats->nodesVisited;
    const glm::vec3 boundsMin = toVec3(node.boundsMin);
    const glm::vec3 boundsMax = toVec3(node.boundsMax);
    if (!mFrusta[transform].intersects(boundsMin, boundsMax)) {
        ++mStats->nodesCulled;
        return Status::ok();
    }

    // ε rule on the cell's bounding sphere, measured at its nearest point to the eye.
    const glm::vec3 cellMin = toVec3(node.cellMin);
    const glm::vec3 cellMax = toVec3(node.cellMax);
    const glm::vec3& localEye = mOut->localEyes[transform];
    const float scale = mTransformScale[transform];
    const float radius = 0.5f * glm::length(cellMax - cellMin) * scale;
    const float distance = glm::length(0.5f * (cellMin + cellMax) - localEye) * scale;
    float projected = INFINITY;
    if (mCamera->orthographic)
        projected = 2.0f * radius * mPixelScale;
    else if (distance > radius)
        projected = 2.0f * radius * mPixelScale / (distance - radius);
    if (projected < mOptions.epsilonPixels && (node.flags & storage::kNodeHasCube)) {
        emitCube(node, transform);
        return Status::ok();
    }

    if (node.kind == static_cast<std::uint8_t>(storage::NodeKind::Instance)) {
        const storage::InstanceRecord& instance = mScene.instances()[node.geometryPage];
        const storage::PrototypeRecord& prototype = mScene.prototypes()[instance.prototype];
        FF_ASSIGN_OR_RETURN(const storage::NodeRecord root, mScene.node(prototype.root));
        ++mStats->instancesEntered;
        const std::uint32_t local = pushTransform(mOut->transforms[transform] * instanceTransform(instance));
        return visit(root, local);
    }

    FF_RETURN_IF_ERROR(emitGeometry(node, transform));

    // Children farthest first, so cubes drawn later blend over what lies behind them.
    const std::size_t base = mChildStack.size();
    for (std::uint32_t c = 0; c < node.childCount; ++c) {
        FF_ASSIGN_OR_RETURN(const storage::NodeRecord child, mScene.child(node, c));
        const glm::vec3 center = 0.5f * (toVec3(child.cellMin) + toVec3(child.cellMax));
        const glm::vec3 d = center - localEye;
        mChildStack.push_back({child, glm::dot(d, d)});
    }
    std::sort(mChildStack.begin() + static_cast<std::ptrdiff_t>(base), mChildStack.end(),
              [](const ChildEntry& a, const ChildEntry& b) { return a.distance > b.distance; });
    for (std::size_t i = base; i < base + node.childCount; ++i) {
        const storage::NodeRecord child = mChildStack[i].record; // the stack may grow below
        FF_RETURN_IF_ERROR(visit(child, transform));
    }
    mChildStack.resize(base);
    return Status::ok();
}

Status Selection::emitGeometry(const storage::NodeRecord& node, std::uint32_t transform) {
    if (node.geometryCount == 0 || node.kind != static_cast<std::uint8_t>(storage::NodeKind::Cell))
        return Status::ok();
    mSegments.clear();
    FF_RETURN_IF_ERROR(mScene.geometrySegments(node, mSegments));
    for (const storage::GeometrySegment& s : mSegments) {
        mOut->geometry.push_back({s.page, s.firstSlot, s.count, transform});
        mStats->trianglesDrawn += s.count;
    }
    return Status::ok();
}

void Selection::emitCube(const storage::NodeRecord& node, std::uint32_t transform) {
    const glm::vec3 boxMin = toVec3(node.cellMin);
    const glm::vec3 boxMax = toVec3(node.cellMax);
    mOut->cubes.push_back({boxMin, boxMax, transform, node.cube});
    ++mStats->cubesDrawn;
    // The faces a viewer can see: those whose outer side holds the eye.
    const glm::vec3& eye = mOut->localEyes[transform];
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
}

Status Selection::collectPrototypeGeometry(std::uint32_t prototype) {
    std::vector<storage::GeometrySegment>& merged = mPrototypeGeometry[prototype];
    std::vector<storage::NodeRecord> stack;
    FF_ASSIGN_OR_RETURN(storage::NodeRecord root, mScene.node(mScene.prototypes()[prototype].root));
    stack.push_back(root);
    std::vector<storage::GeometrySegment> segments;
    while (!stack.empty()) {
        const storage::NodeRecord node = stack.back();
        stack.pop_back();
        segments.clear();
        if (node.geometryCount > 0)
            FF_RETURN_IF_ERROR(mScene.geometrySegments(node, segments));
        merged.insert(merged.end(), segments.begin(), segments.end());
        for (std::uint32_t c = 0; c < node.childCount; ++c) {
            FF_ASSIGN_OR_RETURN(storage::NodeRecord child, mScene.child(node, c));
            stack.push_back(child);
        }
    }
    // Runs that continue one another in a page become one draw.
    std::sort(merged.begin(), merged.end(), [](const auto& a, const auto& b) {
        return a.page != b.page ? a.page < b.page : a.firstSlot < b.firstSlot;
    });
    std::vector<storage::GeometrySegment> out;
    for (const storage::GeometrySegment& s : merged) {
        if (!out.empty() && out.back().page == s.page && out.back().firstSlot + out.back().count == s.firstSlot)
            out.back().count += s.count;
        else
            out.push_back(s);
    }
    merged = std::move(out);
    mPrototypeGeometryReady[prototype] = true;
    return Status::ok();
}

Status Selection::selectFull() {
    const auto& instances = mScene.instances();
    for (const storage::InstanceRecord& instance : instances) {
        if (!mPrototypeGeometryReady[instance.prototype])
            FF_RETURN_IF_ERROR(collectPrototypeGeometry(instance.prototype));
        const std::uint32_t transform = pushTransform(instanceTransform(instance));
        for (const storage::GeometrySegment& s : mPrototypeGeometry[instance.prototype]) {
            mOut->geometry.push_back({s.page, s.firstSlot, s.count, transform});
            mStats->trianglesDrawn += s.count;
        }
    }
    return Status::ok();
}

} // namespace ff::runtime
