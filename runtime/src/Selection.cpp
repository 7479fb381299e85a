// Chamberlain, DeRose, Lischinski, Salesin, Snyder: "Fast Rendering of Complex Environments
// Using a Spatial Hierarchy", GI '96, §3 (the traversal), extended with instancing and with
// streaming (DESIGN.md "Runtime rules": never wait for I/O in a frame).

#include <ff/runtime/Selection.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

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
        const float alpha = (static_cast<float>(node.cube[static_cast<std::size_t>(2 * axis)][3]) +
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

} // namespace

namespace {

constexpr std::array<std::pair<Method, const char*>, 2> kMethods = {{
        {Method::Hierarchical, "hierarchical"},
        {Method::Full, "full"},
}};
constexpr std::array<std::pair<CubeStyle, const char*>, 3> kCubeStyles = {{
        {CubeStyle::Auto, "auto"},
        {CubeStyle::Faces, "faces"},
        {CubeStyle::Points, "points"},
}};

template <typename Enum, std::size_t N>
const char* nameIn(const std::array<std::pair<Enum, const char*>, N>& table, Enum value) noexcept {
    for (const auto& [entry, name] : table) {
        if (entry == value)
            return name;
    }
    return "?";
}

template <typename Enum, std::size_t N>
std::optional<Enum> parseIn(const std::array<std::pair<Enum, const char*>, N>& table, std::string_view text) noexcept {
    for (const auto& [entry, name] : table) {
        if (text == name)
            return entry;
    }
    return std::nullopt;
}

} // namespace

const char* methodName(Method method) noexcept { return nameIn(kMethods, method); }
std::optional<Method> parseMethod(std::string_view name) noexcept { return parseIn(kMethods, name); }
const char* cubeStyleName(CubeStyle style) noexcept { return nameIn(kCubeStyles, style); }
std::optional<CubeStyle> parseCubeStyle(std::string_view name) noexcept { return parseIn(kCubeStyles, name); }

std::vector<std::string> cubeStyleNames() {
    std::vector<std::string> names;
    for (const auto& entry : kCubeStyles)
        names.emplace_back(entry.second);
    return names;
}

Selection::Selection(const storage::SceneFile& scene, IPageAccess& pages)
    : mScene(scene)
    , mPages(pages)
    , mPrototypeGeometry(scene.prototypes().size())
    , mPrototypeGeometryReady(scene.prototypes().size(), false) {}

std::uint32_t Selection::pushTransform(const glm::mat4& transform) {
    const auto index = static_cast<std::uint32_t>(mOut->transforms.size());
    mOut->transforms.push_back(transform);
    mOut->localEyes.push_back(glm::vec3(glm::inverse(transform) * glm::vec4(mCamera->eye, 1.0f)));
    mMetrics.emplace_back(transform);
    const float aspect = mOptions.viewportWidth / std::max(mOptions.viewportHeight, 1.0f);
    mFrusta.emplace_back(mCamera->projection(aspect) * mCamera->view() * transform);
    return index;
}

void Selection::reportFailure(const Status& failure) {
    // Corrupt messages start with "page N: ", so equal messages are the same page's failure.
    if (mReported.insert(failure.message()).second)
        mNewFailures.push_back(failure);
}

Selection::Fetch Selection::fetch(
        std::uint64_t page, storage::PageType type, float priority, std::span<const std::byte>& payload) {
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

Selection::Fetch Selection::readNode(storage::NodeRef ref, float priority, storage::NodeRecord& out) {
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

Selection::Fetch Selection::collectGeometry(const storage::NodeRecord& node, float priority) {
    mSegments.clear();
    if (node.geometryCount == 0 || !isCell(node))
        return Fetch::Ready;
    if (Status status = mScene.geometrySegments(node, mSegments); !status) {
        reportFailure(status);
        return Fetch::Missing;
    }
    // Ask for every page before answering, so all of them are in flight together.
    Fetch result = Fetch::Ready;
    for (const storage::GeometrySegment& s : mSegments) {
        std::span<const std::byte> payload;
        if (fetch(s.page, storage::PageType::Geometry, priority, payload) != Fetch::Ready)
            result = Fetch::Missing;
    }
    return result;
}

Status Selection::select(const Camera& camera, const SelectionOptions& options, DrawList& out, FrameStats& stats) {
    mCamera = &camera;
    mOptions = options;
    mOut = &out;
    mStats = &stats;
    mPixelScale = camera.pixelScale(options.viewportHeight);
    mNewFailures.clear();
    out.clear();
    mMetrics.clear();
    mFrusta.clear();
    mChildStack.clear();
    pushTransform(glm::mat4(1.0f));
    if (options.method == Method::Full) {
        selectFull();
    } else {
        storage::NodeRecord root{};
        if (readNode(mScene.header().root, kTopPriority, root) == Fetch::Ready)
            visit(root, mScene.header().root, 0, 0);
        else if (!mNewFailures.empty())
            return mNewFailures.front().withContext("the root node is unreadable");
    }
    mergeGeometryDraws();
    out.cubesAsPoints = options.cubeStyle == CubeStyle::Points ||
                        (options.cubeStyle == CubeStyle::Auto && options.epsilonPixels <= kAutoPointsMaxEpsilon);
    return Status::ok();
}

void Selection::defer(const storage::NodeRecord& node, storage::NodeRef ref, std::uint32_t transform) {
    ++mStats->nodesDeferred;
    if (node.flags & storage::kNodeHasCube)
        emitCube(node, ref, transform);
}

void Selection::visit(const storage::NodeRecord& node, storage::NodeRef ref, std::uint32_t transform, int depth) {
    if (depth > kMaxNesting) {
        reportFailure(Status(ErrorCode::Corrupt, "node nesting deeper than " + std::to_string(kMaxNesting) +
                                                         " levels: the hierarchy has a reference cycle"));
        return;
    }
    ++mStats->nodesVisited;
    if (!mFrusta[transform].intersects(toVec3(node.boundsMin), toVec3(node.boundsMax))) {
        ++mStats->nodesCulled;
        return;
    }

    // ε rule (Chamberlain et al. '96, §3: a cube is drawn where its "projected screen image is no
    // larger than a pixel"): the area the cell's box covers on screen, seen from the eye's
    // direction at the cell's nearest point, below ε² pixels. The area is a box's silhouette
    // (each face's area times |cos| to the eye), the same measure the point shader draws with,
    // and both it and the distance are taken in world units through the whole transform: an
    // instance may scale its axes differently, mirror or shear.
    const glm::vec3 cellMin = toVec3(node.cellMin);
    const glm::vec3 cellMax = toVec3(node.cellMax);
    const glm::vec3& localEye = mOut->localEyes[transform];
    const TransformMetric& metric = mMetrics[transform];
    const float size = std::sqrt(metric.projectedArea(cellMin, cellMax, localEye)); // a square's side
    const float nearest = metric.nearestDistance(cellMin, cellMax, localEye);
    float projected = INFINITY;
    if (mCamera->orthographic)
        projected = size * mPixelScale;
    else if (nearest > 0.0f)
        projected = size * mPixelScale / nearest;
    if (projected < mOptions.epsilonPixels && (node.flags & storage::kNodeHasCube) &&
        !refusedAsAnisotropic(node, mOptions.maxCubeAnisotropy)) {
        emitCube(node, ref, transform);
        return;
    }
    const float priority = std::min(projected, kTopPriority) * mOptions.priorityScale;

    if (!isCell(node)) {
        const storage::InstanceRecord& instance = mScene.instances()[node.geometryPage];
        const storage::NodeRef rootRef = mScene.prototypes()[instance.prototype].root;
        storage::NodeRecord root{};
        if (readNode(rootRef, priority, root) != Fetch::Ready) {
            defer(node, ref, transform);
            return;
        }
        ++mStats->instancesEntered;
        visit(root, rootRef, pushTransform(mOut->transforms[transform] * instanceTransform(instance)), depth + 1);
        return;
    }

    // Refining needs the cell's own triangles and its children's page; without either, the
    // cell's cube stands in for the whole subtree this frame.
    std::span<const std::byte> childPage;
    const bool childrenReady = node.childCount == 0 ||
                               fetch(node.firstChild.page, storage::PageType::Nodes, priority, childPage) == Fetch::Ready;
    const bool geometryReady = collectGeometry(node, priority) == Fetch::Ready;
    if (!childrenReady || !geometryReady) {
        defer(node, ref, transform);
        return;
    }
    for (const storage::GeometrySegment& s : mSegments) {
        mOut->geometry.push_back({s.page, s.firstSlot, s.count, transform});
        mStats->trianglesDrawn += s.count;
    }

    // Children farthest first (in world distance), so cubes drawn later blend over what lies
    // behind them.
    const std::size_t base = mChildStack.size();
    for (std::uint32_t c = 0; c < node.childCount; ++c) {
        const storage::NodeRef childRef = storage::SceneFile::childRef(node, c);
        Result<storage::NodeRecord> child = mScene.decodeNode(childPage, childRef);
        if (!child) {
            reportFailure(child.status());
            mChildStack.resize(base);
            defer(node, ref, transform);
            return;
        }
        const glm::vec3 d = 0.5f * (toVec3(child->cellMin) + toVec3(child->cellMax)) - localEye;
        mChildStack.push_back({*child, childRef, metric.worldLengthSquared(d)});
    }
    std::sort(mChildStack.begin() + static_cast<std::ptrdiff_t>(base), mChildStack.end(),
              [](const ChildEntry& a, const ChildEntry& b) { return a.distance > b.distance; });
    for (std::size_t i = base; i < base + node.childCount; ++i) {
        const ChildEntry child = mChildStack[i]; // the stack may grow below
        visit(child.record, child.ref, transform, depth + 1);
    }
    mChildStack.resize(base);
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

void Selection::emitCube(const storage::NodeRecord& node, storage::NodeRef ref, std::uint32_t transform) {
    if (mOptions.observer)
        mOptions.observer->cubeDrawn(ref, node);
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

// The whole prototype tree, once, merged into per-page runs. Pages that are not Ready yet
// leave the list incomplete and it is rebuilt on a later frame.
void Selection::collectPrototypeGeometry(std::uint32_t prototype) {
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
    while (!stack.empty()) {
        if (budget-- == 0) {
            reportFailure(Status(ErrorCode::Corrupt, "prototype " + std::to_string(prototype) +
                                                             ": its hierarchy has a reference cycle"));
            break;
        }
        const storage::NodeRecord node = stack.back();
        stack.pop_back();
        if (collectGeometry(node, kTopPriority) != Fetch::Ready)
            complete = false;
        else
            merged.insert(merged.end(), mSegments.begin(), mSegments.end());
        for (std::uint32_t c = 0; c < node.childCount; ++c) {
            storage::NodeRecord child{};
            if (readNode(storage::SceneFile::childRef(node, c), kTopPriority, child) == Fetch::Ready)
                stack.push_back(child);
            else
                complete = false;
        }
    }
    std::sort(merged.begin(), merged.end(), [](const auto& a, const auto& b) {
        return a.page != b.page ? a.page < b.page : a.firstSlot < b.firstSlot;
    });
    std::vector<storage::GeometrySegment> runs;
    for (const storage::GeometrySegment& s : merged) {
        if (!runs.empty() && runs.back().page == s.page && runs.back().firstSlot + runs.back().count == s.firstSlot)
            runs.back().count += s.count;
        else
            runs.push_back(s);
    }
    merged = std::move(runs);
    mPrototypeGeometryReady[prototype] = complete;
}

void Selection::selectFull() {
    for (const storage::InstanceRecord& instance : mScene.instances()) {
        if (!mPrototypeGeometryReady[instance.prototype])
            collectPrototypeGeometry(instance.prototype);
        const std::uint32_t transform = pushTransform(instanceTransform(instance));
        for (const storage::GeometrySegment& s : mPrototypeGeometry[instance.prototype]) {
            std::span<const std::byte> payload;
            if (fetch(s.page, storage::PageType::Geometry, kTopPriority, payload) != Fetch::Ready)
                continue;
            mOut->geometry.push_back({s.page, s.firstSlot, s.count, transform});
            mStats->trianglesDrawn += s.count;
        }
    }
}

} // namespace ff::runtime
