#include "ClusterNodes.h"

#include "LeafCollapse.h"
#include "ParallelFor.h"

#include <ff/builder/ColorCube.h>
#include <ff/storage/Assert.h>

#include <algorithm>
#include <limits>

namespace ff::builder {

namespace {

bool isSplittableLeaf(const BuildNode& node) {
    return node.kind == static_cast<std::uint8_t>(storage::NodeKind::Cell) &&
           node.childCount == 0 && !node.placedChildren && !node.placedTriangles &&
           node.triangleCount > 1;
}

/** The leaves to split, depth first from the root (a placed node's children are elsewhere). */
std::vector<std::uint32_t> splittableLeaves(const std::vector<BuildNode>& nodes) {
    std::vector<std::uint32_t> leaves;
    std::vector<std::uint32_t> stack{0};
    while (!stack.empty()) {
        const std::uint32_t n = stack.back();
        stack.pop_back();
        const BuildNode& node = nodes[n];
        if (isSplittableLeaf(node))
            leaves.push_back(n);
        if (node.placedChildren)
            continue;
        for (std::uint32_t c = node.childCount; c-- > 0;)
            stack.push_back(node.firstChild + c);
    }
    return leaves;
}

/** Reorders `run` into `parts` groups, each a slab of the one before it was cut from (the longest
 *  axis of the centroids, cut in proportion to the parts on each side): as equal in triangles
 *  as the parts allow and spatially compact, so a group's box is mostly covered and its cube
 *  opaque where the surface is. Appends the group sizes in order. */
void splitSpatially(
        std::span<storage::PackedTriangle> run,
        std::uint32_t parts,
        std::vector<std::uint64_t>& sizes) {
    parts = static_cast<std::uint32_t>(std::min<std::uint64_t>(parts, run.size()));
    if (parts <= 1) {
        sizes.push_back(run.size());
        return;
    }
    glm::vec3 lo(std::numeric_limits<float>::max());
    glm::vec3 hi(std::numeric_limits<float>::lowest());
    for (const storage::PackedTriangle& t : run) {
        const glm::vec3 c = centroid(t);
        lo = glm::min(lo, c);
        hi = glm::max(hi, c);
    }
    const glm::vec3 extent = hi - lo;
    const int axis =
            extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
    const std::uint32_t left = parts / 2;
    const std::size_t cut = run.size() * left / parts;
    std::nth_element(
            run.begin(),
            run.begin() + static_cast<std::ptrdiff_t>(cut),
            run.end(),
            [axis](const storage::PackedTriangle& a, const storage::PackedTriangle& b) {
                return centroid(a)[axis] < centroid(b)[axis];
            });
    splitSpatially(run.first(cut), left, sizes);
    splitSpatially(run.subspan(cut), parts - left, sizes);
}

/** Splits one leaf's run: reorders it into spatially compact groups, as many as the clusters it
 *  encodes to (at most kMaxClusterChildren), and returns a child per group (none when it is one
 *  cluster). Touches only `run`. */
class LeafSplitter {
public:
    explicit LeafSplitter(const LeafShapeV2& shape)
        : mShape(shape)
        , mEncoder(shape.limits)
        , mBaker(shape.bakeResolution) {}

    Result<std::vector<BuildNode>>
    split(const BuildNode& leaf, std::span<storage::PackedTriangle> run) {
        FF_ASSIGN_OR_RETURN(
                const std::uint32_t clusters, mEncoder.countClusters(run, *mShape.grid));
        if (clusters <= 1)
            return std::vector<BuildNode>{};
        mSizes.clear();
        splitSpatially(run, std::min(clusters, kMaxClusterChildren), mSizes);

        std::vector<BuildNode> children(mSizes.size());
        std::uint64_t start = 0;
        for (std::size_t c = 0; c < children.size(); ++c) {
            BuildNode& child = children[c];
            const auto own = run.subspan(start, mSizes[c]);
            child.boundsMin = glm::vec3(std::numeric_limits<float>::max());
            child.boundsMax = glm::vec3(std::numeric_limits<float>::lowest());
            for (const storage::PackedTriangle& t : own)
                growBounds(child.boundsMin, child.boundsMax, t);
            child.cellMin = child.boundsMin;
            child.cellMax = child.boundsMax;
            mBaker.reset(child.boundsMin, child.boundsMax);
            mBaker.addTriangles(own);
            child.cube = mBaker.finish();
            FF_ASSERT(leaf.level < 255);
            child.level = static_cast<std::uint8_t>(leaf.level + 1);
            child.kind = static_cast<std::uint8_t>(storage::NodeKind::Cell);
            child.firstTriangle = leaf.firstTriangle + start;
            child.triangleCount = own.size();
            start += own.size();
        }
        return children;
    }

private:
    const LeafShapeV2& mShape;
    ClusterEncoder mEncoder;
    CubeBaker mBaker;
    std::vector<std::uint64_t> mSizes;
};

} // namespace

Result<std::uint64_t> splitLeavesIntoClusters(
        std::vector<BuildNode>& nodes,
        std::span<storage::PackedTriangle> triangles,
        const LeafShapeV2& shape) {
    if (nodes.empty())
        return std::uint64_t{0};
    if (shape.grid == nullptr)
        return Status(ErrorCode::Internal, "cluster nodes without a position grid");
    const std::vector<std::uint32_t> leaves = splittableLeaves(nodes);
    // Each leaf's run is its own (LeafCollapse.h), so leaves split in parallel; the children
    // are appended afterwards in the leaves' order.
    std::vector<std::vector<BuildNode>> children(leaves.size());
    FF_RETURN_IF_ERROR(parallelFor(leaves.size(), shape.threads, [&] {
        return [&, splitter = LeafSplitter(shape)](std::size_t k) mutable -> Status {
            const BuildNode& leaf = nodes[leaves[k]];
            FF_ASSIGN_OR_RETURN(
                    children[k],
                    splitter.split(
                            leaf, triangles.subspan(leaf.firstTriangle, leaf.triangleCount)));
            return Status::ok();
        };
    }));
    std::uint64_t split = 0;
    for (std::size_t k = 0; k < leaves.size(); ++k) {
        if (children[k].empty())
            continue;
        if (nodes.size() + children[k].size() > 0xFFFFFFFFull)
            return Status(ErrorCode::Unsupported, "a hierarchy of more than 2^32 nodes");
        BuildNode& leaf = nodes[leaves[k]];
        leaf.firstChild = static_cast<std::uint32_t>(nodes.size());
        leaf.childCount = static_cast<std::uint32_t>(children[k].size());
        leaf.octreeChildren = false;
        leaf.triangleCount = 0;
        nodes.insert(nodes.end(), children[k].begin(), children[k].end());
        ++split;
    }
    return split;
}

Status shapeLeavesV2(
        std::vector<BuildNode>& nodes,
        std::span<storage::PackedTriangle> triangles,
        const LeafShapeV2& shape) {
    collapseSmallSubtrees(nodes, triangles, shape.leafTriangles);
    if (!shape.clusterNodes)
        return Status::ok();
    return splitLeavesIntoClusters(nodes, triangles, shape).status();
}

} // namespace ff::builder
