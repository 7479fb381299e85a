#include "NodePages.h"

#include "CachedClusterPage.h"

#include <ff/storage/NodeCellV2.h>
#include <ff/storage/NodePageV2.h>

#include <algorithm>
#include <cmath>

namespace ff::runtime::detail {

namespace {

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

} // namespace

glm::mat4 instanceTransform(const storage::InstanceRecord& instance) {
    glm::mat4 m(1.0f);
    for (int row = 0; row < 3; ++row)
        for (int col = 0; col < 4; ++col)
            m[col][row] = instance.transform[static_cast<std::size_t>(row * 4 + col)];
    return m;
}

// ε rule (Chamberlain et al. '96, §3: a cube is drawn where its "projected screen image is no
// larger than a pixel"): the area the cell's box covers on screen, seen from the eye's direction
// at the cell's nearest point, below ε² pixels. The area is a box's silhouette (each face's area
// times |cos| to the eye), the same measure the point shader draws with, and both it and the
// distance are taken in world units through the whole transform: an instance may scale its axes
// differently, mirror or shear.
float projectedPixels(
        const storage::NodeRecord& node,
        const glm::vec3& localEye,
        const TransformMetric& metric,
        const Camera& camera,
        float pixelScale) {
    const glm::vec3 cellMin = toVec3(node.cellMin);
    const glm::vec3 cellMax = toVec3(node.cellMax);
    const float size = std::sqrt(metric.projectedArea(cellMin, cellMax, localEye)); // a side
    if (camera.orthographic)
        return size * pixelScale;
    const float nearest = metric.nearestDistance(cellMin, cellMax, localEye);
    return nearest > 0.0f ? size * pixelScale / nearest : INFINITY;
}

/** `--cube-draw auto` draws points up to this ε: every drawn cube then covers at most 4 pixels,
 *  a point at most 2 pixels wide. */
constexpr float kAutoPointsMaxEpsilon = 2.0f;

bool drawsCubesAsPoints(const SelectionOptions& options) {
    return options.cubeStyle == CubeStyle::AreaWeightedPoints ||
           (options.cubeStyle == CubeStyle::Auto && options.epsilonPixels <= kAutoPointsMaxEpsilon);
}

std::uint32_t cubeFacesToward(
        const storage::NodeRecord& node, const glm::vec3& localEye, std::uint8_t leastAlpha) {
    return cubeFacesToward(toVec3(node.cellMin), toVec3(node.cellMax), node.cube, localEye, leastAlpha);
}

std::uint32_t cubeFacesToward(
        const glm::vec3& lo,
        const glm::vec3& hi,
        const std::array<std::array<std::uint8_t, 4>, storage::kCubeFaceCount>& faces,
        const glm::vec3& localEye,
        std::uint8_t leastAlpha) {
    std::uint32_t toward = 0;
    for (int axis = 0; axis < 3; ++axis) {
        const auto minus = static_cast<std::size_t>(2 * axis);
        if (localEye[axis] < lo[axis] && faces[minus][3] >= leastAlpha)
            ++toward;
        if (localEye[axis] > hi[axis] && faces[minus + 1][3] >= leastAlpha)
            ++toward;
    }
    return toward;
}

bool drawnAsCube(
        const storage::NodeRecord& node, float projected, const SelectionOptions& options) {
    return projected < options.epsilonPixels && (node.flags & storage::kNodeHasCube) &&
           !refusedAsAnisotropic(node, options.maxCubeAnisotropy);
}

// Opaque geometry is depth-tested, so its order is free: sorted by transform and page, runs that
// continue one another become one draw (far fewer draw commands), and both methods submit the
// same triangles in the same order, so ε = 0 reproduces --method full pixel for pixel.
std::size_t mergeGeometryDraws(std::vector<GeometryDraw>& draws) {
    std::sort(draws.begin(), draws.end(), [](const GeometryDraw& a, const GeometryDraw& b) {
        if (a.transform != b.transform)
            return a.transform < b.transform;
        return a.page != b.page ? a.page < b.page : a.first < b.first;
    });
    std::size_t out = 0;
    for (std::size_t i = 0; i < draws.size(); ++i) {
        if (out > 0) {
            GeometryDraw& last = draws[out - 1];
            if (last.transform == draws[i].transform && last.page == draws[i].page &&
                last.first + last.count == draws[i].first) {
                last.count += draws[i].count;
                last.triangles += draws[i].triangles;
                last.pointPixels = std::max(last.pointPixels, draws[i].pointPixels); // never holes
                continue;
            }
        }
        draws[out++] = draws[i];
    }
    draws.resize(out);
    return out;
}

namespace {

/** A representation forced over the cube (`--representation simplified|splats`). */
bool forcesStandIns(Representation representation) noexcept {
    return representation == Representation::Simplified || representation == Representation::Splats;
}

/** Whether `r` is the payload `payload` names. */
bool holds(const storage::RepresentationRecord& r, Payload payload) noexcept {
    switch (payload) {
    case Payload::Own:
        return r.kind == storage::RepresentationKind::Clusters && !storage::isStandIn(r);
    case Payload::Simplified:
        return r.kind == storage::RepresentationKind::Clusters && storage::isStandIn(r);
    case Payload::Splats:
        return r.kind == storage::RepresentationKind::Splats;
    case Payload::Cube:
        return false; // not a representation record: the node's own cube
    }
    return false;
}

} // namespace

Verdict classify(
        const storage::NodeRecord& node,
        const NodeFrame& where,
        const Camera& camera,
        float pixelScale,
        const SelectionOptions& options,
        FrameStats& stats,
        float& projected) {
    ++stats.nodesVisited;
    if (!where.frustum.intersects(toVec3(node.boundsMin), toVec3(node.boundsMax))) {
        ++stats.nodesCulled;
        return Verdict::Culled;
    }
    projected = projectedPixels(node, where.localEye, where.metric, camera, pixelScale);
    if (!drawnAsCube(node, projected, options))
        return Verdict::Refine;
    // `--representation simplified|splats`: a cell with payloads of its own is refined
    // instead, and its stand-in of that kind, if it has one, drawn where auto would draw the
    // cube (standInView).
    const bool mayHaveStandIn = isCell(node) && node.geometryCount > 0;
    return forcesStandIns(options.representation) && mayHaveStandIn ? Verdict::Refine : Verdict::Cube;
}

StandInView standInView(
        const storage::NodeRecord& node,
        const NodeFrame& where,
        const Camera& camera,
        float pixelScale,
        const SelectionOptions& options,
        float projected) {
    StandInView view;
    view.allowed = options.representation != Representation::Cube && options.epsilonPixels > 0.0f;
    view.representation = options.representation;
    view.forced = forcesStandIns(options.representation) && projected < options.epsilonPixels &&
                  (node.flags & storage::kNodeHasCube);
    view.epsilonPixels = options.epsilonPixels;
    view.splatPixels = options.splats.pixels;
    float perUnit = pixelScale * where.metric.maxStretch();
    if (!camera.orthographic) {
        const float nearest =
                where.metric.nearestDistance(toVec3(node.boundsMin), toVec3(node.boundsMax), where.localEye);
        perUnit = nearest > 0.0f ? perUnit / nearest : INFINITY;
    }
    view.pixelsPerUnit = perUnit;
    return view;
}

Status nestingTooDeep() {
    return Status(
            ErrorCode::Corrupt,
            "node nesting deeper than " + std::to_string(kMaxNesting) +
                    " levels: the hierarchy has a reference cycle");
}

void NodePages::reportFailure(const Status& failure) {
    // Corrupt messages start with "page N: ", so equal messages are the same page's failure.
    if (mReported.insert(failure.message()).second)
        mNewFailures.push_back(failure);
}

Fetch NodePages::fetch(
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

namespace {

std::vector<storage::PrototypeRecord> prototypeRecords(const storage::SceneIndex& scene) {
    if (scene.formatVersion() != storage::kFormatVersion2)
        return scene.prototypes();
    std::vector<storage::PrototypeRecord> records;
    records.reserve(scene.prototypesV2().size());
    for (const storage::PrototypeV2& p : scene.prototypesV2()) {
        // The index checked every root against the node slots when it was read.
        const Result<storage::NodeRef> root = scene.nodeLocation(p.rootNode);
        records.push_back(
                {root ? *root : storage::kNullNodeRef,
                 p.bounds.min,
                 p.bounds.max,
                 p.triangleCount,
                 p.nodeCount});
    }
    return records;
}

std::uint32_t bytesOf(std::span<const std::byte> payload) {
    return static_cast<std::uint32_t>(payload.size()); // a page's: far below 4 GiB
}

Status corruptPage(std::uint64_t page, const std::string& what) {
    return Status(ErrorCode::Corrupt, "page " + std::to_string(page) + ": " + what);
}

} // namespace

Result<storage::NodeRef> sceneRoot(const storage::SceneIndex& scene) {
    if (scene.formatVersion() != storage::kFormatVersion2)
        return scene.header().root;
    if ((scene.header().flags & storage::kFileV2HasRoot) == 0)
        return Status(ErrorCode::Corrupt, "page 0: the scene has no root node");
    return scene.nodeLocation(scene.header().root.page);
}

NodePages::NodePages(const storage::SceneIndex& scene, IPageAccess& pages)
    : mScene(scene)
    , mPages(pages)
    , mV2(scene.formatVersion() == storage::kFormatVersion2)
    , mPrototypes(prototypeRecords(scene)) {
    const Result<storage::NodeRef> root = sceneRoot(scene);
    mRoot = root ? *root : storage::kNullNodeRef; // a null root fails as the root's read
}

Fetch NodePages::readTop(
        storage::NodeRef ref,
        const storage::NodeBox& box,
        float priority,
        storage::NodeRecord& out,
        float* subtreeTriangles) {
    if (ref == storage::kNullNodeRef) {
        reportFailure(Status(ErrorCode::Corrupt, "page 0: a hierarchy without a root node"));
        return Fetch::Missing;
    }
    std::span<const std::byte> payload;
    if (fetch(ref.page, storage::PageType::Nodes, priority, payload) != Fetch::Ready)
        return Fetch::Missing;
    Result<storage::NodeRecord> node =
            mV2 ? decodeV2(payload, ref, storage::rootParentV2(box), 0, subtreeTriangles)
                : mScene.decodeNode(payload, ref);
    if (!node) {
        reportFailure(node.status());
        return Fetch::Missing;
    }
    out = *node;
    return Fetch::Ready;
}

Fetch NodePages::root(
        float priority, storage::NodeRef& ref, storage::NodeRecord& out, float* subtreeTriangles) {
    ref = mRoot;
    const storage::FileHeader& h = mScene.header();
    return readTop(ref, {h.boundsMin, h.boundsMax}, priority, out, subtreeTriangles);
}

Fetch NodePages::prototypeRoot(
        std::uint32_t prototype, float priority, storage::NodeRef& ref, storage::NodeRecord& out) {
    const storage::PrototypeRecord& p = mPrototypes[prototype];
    ref = p.root;
    return readTop(ref, {p.boundsMin, p.boundsMax}, priority, out, nullptr);
}

Result<storage::NodeRecord> NodePages::child(
        const storage::NodeRecord& parent,
        std::span<const std::byte> childPage,
        std::uint32_t index,
        float* subtreeTriangles) const {
    const storage::NodeRef ref = storage::SceneIndex::childRef(parent, index);
    if (!mV2)
        return mScene.decodeNode(childPage, ref);
    return decodeV2(
            childPage,
            ref,
            {{parent.boundsMin, parent.boundsMax}, {parent.cellMin, parent.cellMax}},
            static_cast<std::uint8_t>(std::min(parent.level + 1, 255)),
            subtreeTriangles);
}

Result<storage::NodeRecord> NodePages::decodeV2(
        std::span<const std::byte> payload,
        storage::NodeRef ref,
        const storage::DecodedNodeV2& parent,
        std::uint8_t level,
        float* subtreeTriangles) const {
    FF_ASSIGN_OR_RETURN(
            const storage::NodeV2 node,
            storage::readNodeV2(payload, ref.page, ref.slot, parent.bounds));
    if (subtreeTriangles)
        *subtreeTriangles = node.subtreeTriangles; // finite and not negative: readNodeV2
    storage::NodeRecord r{};
    r.boundsMin = node.bounds.min;
    r.boundsMax = node.bounds.max;
    const storage::NodeBox cell = storage::cellOfNode(node, parent.cell);
    r.cellMin = cell.min;
    r.cellMax = cell.max;
    r.cube = node.cube;
    r.childCount = node.childCount;
    r.level = level;
    r.flags = (node.flags & storage::kNodeV2HasCube) ? storage::kNodeHasCube : 0;
    if (node.childCount > 0) {
        // Children are consecutive in one page: the last must be where the first's page ends.
        Result<storage::NodeRef> first = mScene.nodeLocation(node.firstChild);
        if (!first || first->slot + std::uint64_t{node.childCount} >
                              storage::nodesPerPageV2(mScene.pageSize()))
            return corruptPage(
                    ref.page,
                    "node slot " + std::to_string(ref.slot) +
                            ": children outside the node slots or across a page end");
        r.firstChild = *first;
    }
    if (node.kind == storage::NodeKindV2::Instance) {
        if (node.firstRepresentation >= mScene.instances().size())
            return corruptPage(
                    ref.page,
                    "node slot " + std::to_string(ref.slot) + ": instance " +
                            std::to_string(node.firstRepresentation) + " out of range");
        r.kind = static_cast<std::uint8_t>(storage::NodeKind::Instance);
        r.geometryPage = node.firstRepresentation;
    } else {
        r.kind = static_cast<std::uint8_t>(storage::NodeKind::Cell);
        r.geometryPage = ref.page;
        r.geometryFirst = node.firstRepresentation;
        r.geometryCount = node.representationCount;
    }
    return r;
}

Fetch NodePages::childPage(
        const storage::NodeRecord& node, float priority, std::span<const std::byte>& payload) {
    return fetch(node.firstChild.page, storage::PageType::Nodes, priority, payload);
}

Fetch NodePages::collectGeometry(
        const storage::NodeRecord& node,
        float priority,
        IUploadGate& uploads,
        std::vector<PayloadRun>& out) {
    out.clear();
    return admit(payloadRuns(node, priority, out), uploads, out);
}

Fetch NodePages::collectPayload(
        const storage::NodeRecord& node,
        const StandInView& view,
        float priority,
        IUploadGate& uploads,
        std::vector<PayloadRun>& out,
        Payload& drawn) {
    drawn = Payload::Own;
    if (mV2 && view.allowed && isCell(node) && node.geometryCount > 0) {
        if (readRepresentations(node, priority) != Fetch::Ready) {
            out.clear();
            return Fetch::Missing;
        }
        out.clear();
        // The first stand-in `accepted` takes whose pages are ready; `asked` if one is loading.
        bool asked = false;
        const auto firstReady = [&](auto&& accepted) {
            for (const Payload kind : {Payload::Simplified, Payload::Splats}) {
                const storage::RepresentationRecord* kept = keptOf(kind);
                if (kept == nullptr || !accepted(kind, kept->parameter))
                    continue;
                if (drawStandIn(kind, *kept, view, priority, uploads, out) == Fetch::Ready) {
                    drawn = kind;
                    return true;
                }
                asked = true;
            }
            return false;
        };
        if (firstReady([&](Payload kind, float error) { return view.accepts(kind, error); }))
            return Fetch::Ready;
        if (view.forced && keptOf(view.forcedKind()) == nullptr) {
            // The forced kind is not kept here: the nearest kept one, counted. (A forced kind
            // kept but too coarse to draw without holes is refined instead, below: its
            // children's splats are finer.)
            ++mStats->representationFallbacks;
            asked = false;
            if (firstReady([&](Payload kind, float error) { return view.acceptsInstead(kind, error); }))
                return Fetch::Ready;
            if (!asked) {
                drawn = Payload::Cube; // a forced view's cell has one
                return Fetch::Ready;
            }
            // The other stand-in is asked for: refined as without it meanwhile, as in auto.
        }
        return admit(runsOf(priority, out, Payload::Own), uploads, out); // the table read once
    }
    return collectGeometry(node, priority, uploads, out);
}

const storage::RepresentationRecord* NodePages::keptOf(Payload kind) const {
    const auto found = std::find_if(
            mRepresentations.begin(), mRepresentations.end(),
            [kind](const storage::RepresentationRecord& r) { return holds(r, kind); });
    return found == mRepresentations.end() ? nullptr : &*found;
}

Fetch NodePages::drawStandIn(
        Payload kind,
        const storage::RepresentationRecord& kept,
        const StandInView& view,
        float priority,
        IUploadGate& uploads,
        std::vector<PayloadRun>& out) {
    if (admit(runsOf(priority, out, kind), uploads, out) != Fetch::Ready) {
        // Asked for; until it is resident (or if its page failed) the cell is refined as
        // without it, so what was drawn finer does not turn into a cube meanwhile.
        out.clear();
        return Fetch::Missing;
    }
    if (kind == Payload::Splats)
        for (PayloadRun& run : out)
            run.pointPixels = view.splatDiameter(kept.parameter);
    return Fetch::Ready;
}

Fetch NodePages::admit(Fetch result, IUploadGate& uploads, std::vector<PayloadRun>& out) {
    std::size_t kept = 0;
    for (const PayloadRun& run : out) {
        if (!uploads.admit(run.page)) {
            ++mStats->uploadsRefused;
            result = Fetch::Missing;
        } else {
            out[kept++] = run;
        }
    }
    out.resize(kept);
    return result;
}

Fetch NodePages::payloadRuns(
        const storage::NodeRecord& node, float priority, std::vector<PayloadRun>& out) {
    if (node.geometryCount == 0 || !isCell(node))
        return Fetch::Ready;
    if (mV2)
        return clusterRuns(node, priority, out, Payload::Own);
    mRuns.clear();
    if (Status status = mScene.geometrySegments(node, mRuns); !status) {
        reportFailure(status);
        return Fetch::Missing;
    }
    Fetch result = Fetch::Ready;
    for (const storage::GeometrySegment& s : mRuns) {
        std::span<const std::byte> payload;
        if (fetch(s.page, storage::PageType::Geometry, priority, payload) != Fetch::Ready)
            result = Fetch::Missing;
        else
            out.push_back(
                    {s.page, payload.data(), s.firstSlot, s.count, s.count, bytesOf(payload)});
    }
    return result;
}

Fetch NodePages::readRepresentations(const storage::NodeRecord& node, float priority) {
    std::span<const std::byte> nodePage;
    if (fetch(node.geometryPage, storage::PageType::Nodes, priority, nodePage) != Fetch::Ready)
        return Fetch::Missing;
    storage::NodeV2 cell;
    cell.firstRepresentation = node.geometryFirst;
    cell.representationCount = static_cast<std::uint8_t>(node.geometryCount);
    mRepresentations.clear();
    if (Status status = storage::readRepresentationsV2(
                nodePage, node.geometryPage, cell, mRepresentations);
        !status) {
        reportFailure(status);
        return Fetch::Missing;
    }
    return Fetch::Ready;
}

// A format 2 cell's payloads: its representations, in its own page, name runs of whole clusters
// in cluster pages as the cache keeps them (CachedClusterPage). Kinds this build does not draw are
// passed over, so a file with a later issue's kinds still draws its clusters.
Fetch NodePages::clusterRuns(
        const storage::NodeRecord& node, float priority, std::vector<PayloadRun>& out, Payload which) {
    if (readRepresentations(node, priority) != Fetch::Ready)
        return Fetch::Missing;
    return runsOf(priority, out, which);
}

Fetch NodePages::runsOf(float priority, std::vector<PayloadRun>& out, Payload which) {
    Fetch result = Fetch::Ready;
    for (const storage::RepresentationRecord& r : mRepresentations) {
        if (!holds(r, which))
            continue;
        std::span<const std::byte> payload;
        if (fetch(r.page, storage::PageType::Geometry, priority, payload) != Fetch::Ready) {
            result = Fetch::Missing;
            continue;
        }
        Result<CachedClusterPage> page = CachedClusterPage::view(payload);
        Result<storage::ClusterRun> run =
                page ? page->run(r.offset, r.length, r.count) : Result<storage::ClusterRun>(page.status());
        if (!run) {
            reportFailure(corruptPage(r.page, run.status().message()));
            result = Fetch::Missing;
            continue;
        }
        std::uint32_t triangles = 0;
        std::uint32_t points = 0;
        for (const storage::IndexedCluster& cluster : page->clusters(run->first, run->count)) {
            triangles += cluster.info.triangleCount;
            points += cluster.info.points() ? cluster.info.vertexCount : 0;
        }
        out.push_back({r.page, payload.data(), run->first, run->count, triangles, bytesOf(payload), points});
    }
    return result;
}

} // namespace ff::runtime::detail
