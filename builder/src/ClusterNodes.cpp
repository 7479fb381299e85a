#include "ClusterNodes.h"

#include "LeafCollapse.h"
#include "ParallelFor.h"

#include <ff/builder/ColorCube.h>
#include <ff/storage/Assert.h>

#include <algorithm>
#include <cmath>
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

/** A stretch of a leaf's run that becomes a node: `parts` pieces of about a cluster. */
struct Group {
    std::uint64_t start = 0; ///< into the leaf's run
    std::uint64_t size = 0;
    std::uint32_t parts = 1;
};

/** Reorders the triangles of `groups` (consecutive in `run`, from `start`) so each group is a
 *  slab of the stretch it was cut from — the longest axis of the centroids, cut in proportion to
 *  the parts on each side — then gives each group its size: as equal in triangles as the parts
 *  allow and spatially compact, so a group's box is mostly covered and its cube opaque where
 *  the surface is. */
void cutIntoSlabs(
        std::span<storage::PackedTriangle> run, std::uint64_t start, std::span<Group> groups) {
    std::uint64_t total = 0;
    for (const Group& g : groups)
        total += g.parts;
    const auto stretch = run.subspan(start, groups.front().size);
    if (groups.size() == 1)
        return;
    glm::vec3 lo(std::numeric_limits<float>::max());
    glm::vec3 hi(std::numeric_limits<float>::lowest());
    for (const storage::PackedTriangle& t : stretch) {
        const glm::vec3 c = centroid(t);
        lo = glm::min(lo, c);
        hi = glm::max(hi, c);
    }
    const glm::vec3 extent = hi - lo;
    const int axis =
            extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
    const std::size_t half = groups.size() / 2;
    std::uint64_t leftParts = 0;
    for (std::size_t g = 0; g < half; ++g)
        leftParts += groups[g].parts;
    // Each side keeps at least a triangle per group, so no node is empty.
    const std::uint64_t cut = std::clamp<std::uint64_t>(
            stretch.size() * leftParts / total, half, stretch.size() - (groups.size() - half));
    std::nth_element(
            stretch.begin(),
            stretch.begin() + static_cast<std::ptrdiff_t>(cut),
            stretch.end(),
            [axis](const storage::PackedTriangle& a, const storage::PackedTriangle& b) {
                return centroid(a)[axis] < centroid(b)[axis];
            });
    groups.front().size = cut;
    groups[half].size = stretch.size() - cut;
    cutIntoSlabs(run, start, groups.first(half));
    cutIntoSlabs(run, start + cut, groups.subspan(half));
}

/** Splits `group` into at most kClusterNodeBranching groups of as equal parts as they can be,
 *  reordering its triangles (cutIntoSlabs). */
std::vector<Group> splitGroup(std::span<storage::PackedTriangle> run, const Group& group) {
    const std::uint32_t ways = std::min(
            {group.parts,
             kClusterNodeBranching,
             static_cast<std::uint32_t>(std::min<std::uint64_t>(group.size, 0xFFFFFFFFu))});
    std::vector<Group> groups(ways);
    for (std::uint32_t g = 0; g < ways; ++g)
        groups[g].parts = group.parts / ways + (g < group.parts % ways ? 1 : 0);
    groups.front().size = group.size;
    cutIntoSlabs(run, group.start, groups);
    std::uint64_t start = group.start;
    for (Group& g : groups) {
        g.start = start;
        start += g.size;
    }
    return groups;
}

/** The nodes below a split leaf, breadth first: the leaf's own `direct` children first, then
 *  theirs; `firstChild` counts from the front of `nodes`. */
struct SplitTree {
    std::vector<BuildNode> nodes;
    std::uint32_t direct = 0;
};

/** Splits one leaf's run into a tree of nodes below it, each at most kClusterNodeBranching
 *  children wide, whose leaves are spatially compact pieces of about a cluster, as many as the
 *  clusters the run encodes to times kPiecesPerCluster (none when it is one cluster). Touches
 *  only `run`. */
class LeafSplitter {
public:
    explicit LeafSplitter(const LeafShapeV2& shape)
        : mShape(shape)
        , mEncoder(shape.limits)
        , mBaker(shape.bakeResolution) {}

    Result<SplitTree>
    split(const BuildNode& leaf, std::span<storage::PackedTriangle> run) {
        FF_ASSIGN_OR_RETURN(
                const std::uint32_t clusters, mEncoder.countClusters(run, *mShape.grid));
        if (clusters <= 1)
            return SplitTree{};
        const auto pieces = static_cast<std::uint32_t>(std::min<double>(
                std::ceil(clusters * kPiecesPerCluster), static_cast<double>(run.size())));
        SplitTree out;
        std::vector<BuildNode>& tree = out.nodes;
        std::vector<Group> groups; // tree[i] is groups[i]
        const auto addChildren = [&](const Group& parent, std::uint8_t parentLevel) {
            FF_ASSERT(parentLevel < 255);
            for (const Group& g : splitGroup(run, parent)) {
                groups.push_back(g);
                tree.push_back(node(leaf, run, g, static_cast<std::uint8_t>(parentLevel + 1)));
            }
        };
        addChildren({0, run.size(), pieces}, leaf.level);
        out.direct = static_cast<std::uint32_t>(tree.size());
        for (std::size_t i = 0; i < tree.size(); ++i) {
            if (groups[i].parts <= 1)
                continue;
            tree[i].firstChild = static_cast<std::uint32_t>(tree.size());
            tree[i].triangleCount = 0;
            const Group group = groups[i];
            const std::uint8_t level = tree[i].level;
            addChildren(group, level);
            tree[i].childCount = static_cast<std::uint32_t>(tree.size()) - tree[i].firstChild;
        }
        return out;
    }

private:
    /** The node of `group`: its bounds, its cube baked on them, its triangles (kept when it
     *  becomes a parent: cubes of inner nodes are baked before they are split further). */
    BuildNode node(
            const BuildNode& leaf,
            std::span<const storage::PackedTriangle> run,
            const Group& group,
            std::uint8_t level) {
        BuildNode out;
        const auto own = run.subspan(group.start, group.size);
        out.boundsMin = glm::vec3(std::numeric_limits<float>::max());
        out.boundsMax = glm::vec3(std::numeric_limits<float>::lowest());
        for (const storage::PackedTriangle& t : own)
            growBounds(out.boundsMin, out.boundsMax, t);
        out.cellMin = out.boundsMin;
        out.cellMax = out.boundsMax;
        mBaker.reset(out.boundsMin, out.boundsMax);
        mBaker.addTriangles(own);
        out.cube = mBaker.finish();
        out.level = level;
        out.kind = static_cast<std::uint8_t>(storage::NodeKind::Cell);
        out.firstTriangle = leaf.firstTriangle + group.start;
        out.triangleCount = own.size();
        return out;
    }

    const LeafShapeV2& mShape;
    ClusterEncoder mEncoder;
    CubeBaker mBaker;
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
    std::vector<SplitTree> below(leaves.size());
    FF_RETURN_IF_ERROR(parallelFor(leaves.size(), shape.threads, [&] {
        return [&, splitter = LeafSplitter(shape)](std::size_t k) mutable -> Status {
            const BuildNode& leaf = nodes[leaves[k]];
            FF_ASSIGN_OR_RETURN(
                    below[k],
                    splitter.split(
                            leaf, triangles.subspan(leaf.firstTriangle, leaf.triangleCount)));
            return Status::ok();
        };
    }));
    std::uint64_t split = 0;
    for (std::size_t k = 0; k < leaves.size(); ++k) {
        std::vector<BuildNode>& tree = below[k].nodes;
        if (tree.empty())
            continue;
        if (nodes.size() + tree.size() > 0xFFFFFFFFull)
            return Status(ErrorCode::Unsupported, "a hierarchy of more than 2^32 nodes");
        const auto base = static_cast<std::uint32_t>(nodes.size());
        for (BuildNode& node : tree)
            if (node.childCount > 0)
                node.firstChild += base;
        BuildNode& leaf = nodes[leaves[k]];
        leaf.firstChild = base;
        leaf.childCount = below[k].direct;
        leaf.octreeChildren = false;
        leaf.triangleCount = 0;
        nodes.insert(nodes.end(), tree.begin(), tree.end());
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
