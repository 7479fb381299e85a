#include "NodePages.h"

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
    return out;
}

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
    return drawnAsCube(node, projected, options) ? Verdict::Cube : Verdict::Refine;
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

Fetch NodePages::readNode(storage::NodeRef ref, float priority, storage::NodeRecord& out) {
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
    if (node.geometryCount == 0 || !isCell(node))
        return Fetch::Ready;
    mRuns.clear();
    if (Status status = mScene.geometrySegments(node, mRuns); !status) {
        reportFailure(status);
        return Fetch::Missing;
    }
    Fetch result = Fetch::Ready;
    for (const storage::GeometrySegment& s : mRuns) {
        std::span<const std::byte> payload;
        if (fetch(s.page, storage::PageType::Geometry, priority, payload) != Fetch::Ready) {
            result = Fetch::Missing;
        } else if (!uploads.admit(s.page)) {
            ++mStats->uploadsRefused;
            result = Fetch::Missing;
        } else {
            out.push_back({s, payload.data()});
        }
    }
    return result;
}

} // namespace ff::runtime::detail
