#include "InstanceLevel.h"

#include "Decomposition.h"
#include "SubtreeEncoder.h"

#include <ff/storage/NodeCellV2.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

namespace ff::builder {

namespace {

constexpr int kMaxInstanceDepth = 24;
constexpr std::uint32_t kMaxGroupChildren = 8;

struct PlacedInstance {
    glm::mat4 transform{1.0f};
    glm::vec3 worldMin{0.0f};
    glm::vec3 worldMax{0.0f};
    glm::vec3 center{0.0f};
    std::uint32_t prototype = 0;
};

class InstanceHierarchy {
public:
    InstanceHierarchy(
            std::vector<PlacedInstance> placed,
            const std::vector<PrototypeSummary>& summaries,
            const HierarchyParams& params)
        : mPlaced(std::move(placed))
        , mSummaries(summaries)
        , mParams(params)
        , mBaker(params.bakeResolution) {
        mOrder.resize(mPlaced.size());
        std::iota(mOrder.begin(), mOrder.end(), 0u);
    }

    std::vector<BuildNode> run(const Cell& root) {
        mNodes.emplace_back();
        // ORSD decomposes voxel grids; instances have none, so their level is an octree.
        if (mParams.decomposition == Decomposition::Octree || mParams.decomposition == Decomposition::Orsd) {
            buildCell(0, root, 0, mOrder.size(), 0, 0);
            return std::move(mNodes);
        }
        std::vector<SplitItem> items(mPlaced.size());
        for (std::size_t i = 0; i < mPlaced.size(); ++i)
            items[i] = {mPlaced[i].worldMin, mPlaced[i].worldMax, mPlaced[i].center};
        // An instance is one item; a leaf holds about a group's worth of them.
        DecompositionParams split = mParams.split;
        split.minTriangles = kMaxGroupChildren;
        split.maxTriangles = kMaxGroupChildren;
        split.balancedMinTriangles = 2;
        split.maxDepth = std::min(split.maxDepth, kMaxInstanceDepth);
        const std::vector<SplitNode> nodes = decompose(items, mOrder, mParams.decomposition, split);
        mNodes[0].cellMin = root.min;
        mNodes[0].cellMax = root.max();
        buildSplit(0, nodes, 0);
        return std::move(mNodes);
    }

    std::uint32_t depth() const { return mDepth; }

private:
    void buildCell(std::size_t index, const Cell& cell, std::size_t begin, std::size_t end, int level, int octant) {
        mDepth = std::max(mDepth, static_cast<std::uint32_t>(level));
        {
            BuildNode& node = mNodes[index];
            node.cellMin = cell.min;
            node.cellMax = cell.max();
            node.level = static_cast<std::uint8_t>(level);
            node.octant = static_cast<std::uint8_t>(octant);
            node.kind = static_cast<std::uint8_t>(storage::NodeKind::Cell);
        }
        const auto first = mOrder.begin() + static_cast<std::ptrdiff_t>(begin);
        const auto last = mOrder.begin() + static_cast<std::ptrdiff_t>(end);
        const bool allSame = std::all_of(first, last, [&](std::uint32_t i) { return mPlaced[i].center == mPlaced[*first].center; });
        if (level >= kMaxInstanceDepth || allSame) {
            buildGroup(index, begin, end, level);
            return;
        }
        // Stable sort by octant keeps the output independent of partition internals.
        std::stable_sort(first, last, [&](std::uint32_t a, std::uint32_t b) {
            return octantOf(cell, mPlaced[a].center) < octantOf(cell, mPlaced[b].center);
        });
        std::array<std::size_t, 9> runs{};
        runs[0] = begin;
        std::size_t cursor = begin;
        for (int o = 0; o < 8; ++o) {
            while (cursor < end && octantOf(cell, mPlaced[mOrder[cursor]].center) == o)
                ++cursor;
            runs[static_cast<std::size_t>(o + 1)] = cursor;
        }
        std::uint32_t childCount = 0;
        for (int o = 0; o < 8; ++o)
            childCount += runs[static_cast<std::size_t>(o + 1)] > runs[static_cast<std::size_t>(o)] ? 1u : 0u;
        const auto firstChild = static_cast<std::uint32_t>(mNodes.size());
        mNodes[index].firstChild = firstChild;
        mNodes[index].childCount = childCount;
        mNodes[index].octreeChildren = true;
        mNodes.resize(mNodes.size() + childCount);
        std::uint32_t child = firstChild;
        for (int o = 0; o < 8; ++o) {
            const std::size_t b = runs[static_cast<std::size_t>(o)];
            const std::size_t e = runs[static_cast<std::size_t>(o + 1)];
            if (e == b)
                continue;
            if (e - b == 1)
                buildInstance(child, mOrder[b], level + 1, o);
            else
                buildCell(child, cell.octantCell(o), b, e, level + 1, o);
            ++child;
        }
        finishNode(index, begin, end);
    }

    // A node of a bounding-volume decomposition (Decomposition.h); `index`'s cell is set.
    void buildSplit(std::size_t index, const std::vector<SplitNode>& split, std::size_t at) {
        const SplitNode& s = split[at];
        mDepth = std::max(mDepth, static_cast<std::uint32_t>(s.level));
        BuildNode& node = mNodes[index];
        node.level = static_cast<std::uint8_t>(s.level);
        node.kind = static_cast<std::uint8_t>(storage::NodeKind::Cell);
        if (s.childCount == 0) {
            buildGroup(index, s.begin, s.end, s.level);
            return;
        }
        const auto firstChild = static_cast<std::uint32_t>(mNodes.size());
        node.firstChild = firstChild;
        node.childCount = s.childCount;
        mNodes.resize(mNodes.size() + s.childCount); // `node` is invalid from here
        for (std::uint32_t c = 0; c < s.childCount; ++c) {
            const SplitNode& child = split[s.firstChild + c];
            if (child.end - child.begin == 1) {
                buildInstance(firstChild + c, mOrder[child.begin], s.level + 1, 0);
                continue;
            }
            mNodes[firstChild + c].cellMin = child.cellMin;
            mNodes[firstChild + c].cellMax = child.cellMax;
            buildSplit(firstChild + c, split, s.firstChild + c);
        }
        finishNode(index, s.begin, s.end);
    }

    // Instances that space cannot separate (same centre, or too deep): split the list instead.
    void buildGroup(std::size_t index, std::size_t begin, std::size_t end, int level) {
        const std::size_t count = end - begin;
        const std::uint32_t childCount = static_cast<std::uint32_t>(std::min<std::size_t>(count, kMaxGroupChildren));
        const auto firstChild = static_cast<std::uint32_t>(mNodes.size());
        mNodes[index].firstChild = firstChild;
        mNodes[index].childCount = childCount;
        mNodes.resize(mNodes.size() + childCount);
        for (std::uint32_t c = 0; c < childCount; ++c) {
            const std::size_t b = begin + count * c / childCount;
            const std::size_t e = begin + count * (c + 1) / childCount;
            const std::uint32_t child = firstChild + c;
            if (e - b == 1) {
                buildInstance(child, mOrder[b], level + 1, 0);
                continue;
            }
            BuildNode& node = mNodes[child];
            node.cellMin = mNodes[index].cellMin;
            node.cellMax = mNodes[index].cellMax;
            node.level = static_cast<std::uint8_t>(level + 1);
            node.kind = static_cast<std::uint8_t>(storage::NodeKind::Cell);
            buildGroup(child, b, e, level + 1);
        }
        finishNode(index, begin, end);
    }

    void buildInstance(std::size_t index, std::uint32_t instance, int level, int octant) {
        mDepth = std::max(mDepth, static_cast<std::uint32_t>(level));
        BuildNode& node = mNodes[index];
        const PlacedInstance& placed = mPlaced[instance];
        node.kind = static_cast<std::uint8_t>(storage::NodeKind::Instance);
        node.instanceIndex = instance;
        node.level = static_cast<std::uint8_t>(level);
        node.octant = static_cast<std::uint8_t>(octant);
        node.cellMin = placed.worldMin;
        node.cellMax = placed.worldMax;
        node.boundsMin = placed.worldMin;
        node.boundsMax = placed.worldMax;
        mBaker.reset(node.cellMin, node.cellMax);
        addInstanceBoxes(placed, node.cellMax - node.cellMin);
        node.cube = mBaker.finish();
    }

    void finishNode(std::size_t index, std::size_t begin, std::size_t end) {
        BuildNode& node = mNodes[index];
        node.boundsMin = glm::vec3(std::numeric_limits<float>::infinity());
        node.boundsMax = glm::vec3(-std::numeric_limits<float>::infinity());
        for (std::size_t i = begin; i < end; ++i) {
            node.boundsMin = glm::min(node.boundsMin, mPlaced[mOrder[i]].worldMin);
            node.boundsMax = glm::max(node.boundsMax, mPlaced[mOrder[i]].worldMax);
        }
        mBaker.reset(node.cellMin, node.cellMax);
        for (std::size_t i = begin; i < end; ++i)
            addInstanceBoxes(mPlaced[mOrder[i]], node.cellMax - node.cellMin);
        node.cube = mBaker.finish();
    }

    // Adds the prototype cut whose cells are about two bake samples of this cell across: finer
    // cuts cost 8x more boxes per level and change the baked faces by little (measured on the
    // forest: see docs/results), and a flat cell must not ask for the finest cut.
    void addInstanceBoxes(const PlacedInstance& placed, const glm::vec3& cellSize) {
        const PrototypeSummary& summary = mSummaries[placed.prototype];
        const float sample = 2.0f * std::max({cellSize.x, cellSize.y, cellSize.z}) / static_cast<float>(mBaker.resolution());
        const float scale = std::max({glm::length(glm::vec3(placed.transform[0])),
                                      glm::length(glm::vec3(placed.transform[1])),
                                      glm::length(glm::vec3(placed.transform[2]))});
        int level = 0;
        while (level < PrototypeSummary::kDepth && summary.rootCellSize * scale / std::ldexp(1.0f, level) > sample)
            ++level;
        for (const SummaryBox& box : summary.cuts[static_cast<std::size_t>(level)])
            mBaker.addBox(placed.transform, box.cellMin, box.cellMax, box.cube);
    }

    std::vector<PlacedInstance> mPlaced;
    const std::vector<PrototypeSummary>& mSummaries;
    const HierarchyParams& mParams;
    CubeBaker mBaker;
    std::vector<std::uint32_t> mOrder;
    std::vector<BuildNode> mNodes;
    std::uint32_t mDepth = 0;
};

} // namespace

glm::mat4 toMat4(const std::array<float, 12>& m) {
    glm::mat4 out(1.0f);
    for (int row = 0; row < 3; ++row)
        for (int col = 0; col < 4; ++col)
            out[col][row] = m[static_cast<std::size_t>(row * 4 + col)];
    return out;
}

std::array<float, 12> toRowMajor3x4(const glm::mat4& m) {
    std::array<float, 12> out{};
    for (int row = 0; row < 3; ++row)
        for (int col = 0; col < 4; ++col)
            out[static_cast<std::size_t>(row * 4 + col)] = m[col][row];
    return out;
}

Result<InstanceLevelResult> buildInstanceLevel(
        storage::SceneWriter& writer,
        const std::vector<storage::InstanceRecord>& instances,
        const std::vector<storage::PrototypeRecord>& prototypes,
        const std::vector<PrototypeSummary>& summaries,
        const HierarchyParams& params,
        NodePageTable* nodePageTable) {
    if (instances.empty())
        return Status(ErrorCode::InvalidInput, "the scene has no triangles to draw");
    std::vector<PlacedInstance> placed(instances.size());
    glm::vec3 lo(std::numeric_limits<float>::infinity());
    glm::vec3 hi(-std::numeric_limits<float>::infinity());
    for (std::size_t i = 0; i < instances.size(); ++i) {
        PlacedInstance& p = placed[i];
        p.prototype = instances[i].prototype;
        p.transform = toMat4(instances[i].transform);
        const storage::PrototypeRecord& proto = prototypes[p.prototype];
        p.worldMin = glm::vec3(std::numeric_limits<float>::infinity());
        p.worldMax = glm::vec3(-std::numeric_limits<float>::infinity());
        for (int k = 0; k < 8; ++k) {
            const glm::vec3 local(
                    proto.boundsMin[0] + ((k & 1) ? proto.boundsMax[0] - proto.boundsMin[0] : 0.0f),
                    proto.boundsMin[1] + ((k & 2) ? proto.boundsMax[1] - proto.boundsMin[1] : 0.0f),
                    proto.boundsMin[2] + ((k & 4) ? proto.boundsMax[2] - proto.boundsMin[2] : 0.0f));
            const glm::vec3 world(p.transform * glm::vec4(local, 1.0f));
            p.worldMin = glm::min(p.worldMin, world);
            p.worldMax = glm::max(p.worldMax, world);
        }
        if (!std::isfinite(p.worldMin.x + p.worldMin.y + p.worldMin.z + p.worldMax.x + p.worldMax.y + p.worldMax.z))
            return Status(ErrorCode::InvalidInput, "instance " + std::to_string(i) + ": transform is not finite");
        p.center = 0.5f * (p.worldMin + p.worldMax);
        lo = glm::min(lo, p.worldMin);
        hi = glm::max(hi, p.worldMax);
    }
    const glm::vec3 size = hi - lo;
    const Cell root{lo, storage::rootCellEdge({size.x, size.y, size.z})}; // as NodeCellV2.h reads it

    InstanceHierarchy hierarchy(std::move(placed), summaries, params);
    std::vector<BuildNode> nodes = hierarchy.run(root);
    InstanceLevelResult result;
    result.boundsMin = nodes[0].boundsMin;
    result.boundsMax = nodes[0].boundsMax;
    result.depth = hierarchy.depth();
    if (writer.formatVersion() == storage::kFormatVersion2) {
        if (nodePageTable == nullptr)
            return Status(ErrorCode::Internal, "a format 2 instance level without a node page table");
        std::vector<std::uint64_t> drawn(instances.size());
        for (std::size_t i = 0; i < instances.size(); ++i)
            drawn[i] = prototypes[instances[i].prototype].triangleCount;
        SubtreeV2Input input;
        input.rootParent = storage::rootParentV2({{result.boundsMin.x, result.boundsMin.y, result.boundsMin.z},
                                         {result.boundsMax.x, result.boundsMax.y, result.boundsMax.z}});
        input.instanceTriangles = drawn;
        FF_ASSIGN_OR_RETURN(const SubtreeV2Result written, writeSubtreeV2(writer, *nodePageTable, std::move(nodes), {}, input));
        result.nodes = written.nodes;
        result.nodePages = written.nodePages;
        result.rootNode = written.rootNode;
        return result;
    }
    EncodedSubtree encoded = encodeSubtree(std::move(nodes), {}, writer.pageSize());
    result.nodes = encoded.nodeCount;
    result.nodePages = encoded.nodePages.size();
    FF_RETURN_IF_ERROR(commitSubtree(writer, encoded));
    result.root = encoded.rootRef;
    return result;
}

} // namespace ff::builder
