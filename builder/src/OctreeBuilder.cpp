// Adaptive octree with Chamberlain et al.'s cost-based subdivision (GI '96, §4) and Wand &
// Strasser's tolerance rule for large triangles (EG '02, §3.1).

#include "OctreeBuilder.h"

#include <algorithm>
#include <array>
#include <limits>

namespace ff::builder {

namespace {

glm::vec3 toVec3(const std::array<float, 3>& a) { return {a[0], a[1], a[2]}; }

class OctreeRecursion {
public:
    OctreeRecursion(
            std::vector<storage::PackedTriangle>& triangles,
            const HierarchyParams& params,
            CubeBaker& baker)
        : mTriangles(triangles)
        , mParams(params)
        , mBaker(baker) {}

    std::vector<BuildNode> run(const Cell& cell, int level, int octant) {
        mNodes.clear();
        mNodes.emplace_back();
        build(0, cell, 0, mTriangles.size(), level, octant);
        return std::move(mNodes);
    }

private:
    using Iterator = std::vector<storage::PackedTriangle>::iterator;

    // Splits [begin, end) by the octant of each centroid into eight consecutive runs.
    std::array<std::uint64_t, 9> partitionByOctant(const Cell& cell, std::uint64_t begin, std::uint64_t end) {
        const glm::vec3 center = cell.min + glm::vec3(0.5f * cell.size);
        const auto first = mTriangles.begin() + static_cast<std::ptrdiff_t>(begin);
        const auto last = mTriangles.begin() + static_cast<std::ptrdiff_t>(end);
        auto below = [&](int axis) {
            return [&center, axis](const storage::PackedTriangle& t) { return centroid(t)[axis] < center[axis]; };
        };
        // z splits the run in two, y each half, x each quarter: runs end up in octant order.
        const Iterator zSplit = std::partition(first, last, below(2));
        const std::array<Iterator, 3> zBounds = {first, zSplit, last};
        std::array<Iterator, 5> yBounds;
        for (int h = 0; h < 2; ++h) {
            yBounds[static_cast<std::size_t>(2 * h)] = zBounds[static_cast<std::size_t>(h)];
            yBounds[static_cast<std::size_t>(2 * h + 1)] =
                    std::partition(zBounds[static_cast<std::size_t>(h)], zBounds[static_cast<std::size_t>(h + 1)], below(1));
        }
        yBounds[4] = last;
        std::array<std::uint64_t, 9> bounds{};
        for (int q = 0; q < 4; ++q) {
            const Iterator qBegin = yBounds[static_cast<std::size_t>(q)];
            const Iterator qEnd = yBounds[static_cast<std::size_t>(q + 1)];
            const Iterator xSplit = std::partition(qBegin, qEnd, below(0));
            bounds[static_cast<std::size_t>(2 * q)] = static_cast<std::uint64_t>(qBegin - mTriangles.begin());
            bounds[static_cast<std::size_t>(2 * q + 1)] = static_cast<std::uint64_t>(xSplit - mTriangles.begin());
        }
        bounds[8] = end;
        return bounds;
    }

    void build(std::size_t nodeIndex, const Cell& cell, std::uint64_t begin, std::uint64_t end, int level, int octant) {
        // Large triangles first: they stay here whatever happens below.
        const float limit = mParams.largeTriangleTolerance * cell.size;
        const auto first = mTriangles.begin() + static_cast<std::ptrdiff_t>(begin);
        const auto last = mTriangles.begin() + static_cast<std::ptrdiff_t>(end);
        const Iterator smallBegin =
                std::partition(first, last, [limit](const storage::PackedTriangle& t) { return extent(t) > limit; });
        const auto ownEnd = static_cast<std::uint64_t>(smallBegin - mTriangles.begin());
        const std::uint64_t descending = end - ownEnd;

        std::array<std::uint64_t, 9> runs{};
        int nonEmpty = 0;
        bool subdivide = false;
        if (descending > 0 && level < mParams.maxDepth) {
            runs = partitionByOctant(cell, ownEnd, end);
            for (int o = 0; o < 8; ++o)
                nonEmpty += runs[static_cast<std::size_t>(o + 1)] > runs[static_cast<std::size_t>(o)] ? 1 : 0;
            // Chamberlain's rule: stop where drawing the triangles costs no more than drawing
            // the children's cubes.
            subdivide = static_cast<float>(descending) > static_cast<float>(nonEmpty) * mParams.cubeCost;
        }

        {
            BuildNode& node = mNodes[nodeIndex];
            node.cellMin = cell.min;
            node.cellMax = cell.max();
            node.level = static_cast<std::uint8_t>(level);
            node.octant = static_cast<std::uint8_t>(octant);
            node.kind = static_cast<std::uint8_t>(storage::NodeKind::Cell);
            node.firstTriangle = begin;
            node.triangleCount = subdivide ? ownEnd - begin : end - begin;
            node.boundsMin = glm::vec3(std::numeric_limits<float>::infinity());
            node.boundsMax = glm::vec3(-std::numeric_limits<float>::infinity());
            for (std::uint64_t i = begin; i < begin + node.triangleCount; ++i)
                growBounds(node.boundsMin, node.boundsMax, mTriangles[i]);
        }

        if (subdivide) {
            const auto firstChild = static_cast<std::uint32_t>(mNodes.size());
            mNodes[nodeIndex].firstChild = firstChild;
            mNodes[nodeIndex].childCount = static_cast<std::uint32_t>(nonEmpty);
            mNodes[nodeIndex].octreeChildren = true;
            mNodes.resize(mNodes.size() + static_cast<std::size_t>(nonEmpty));
            std::uint32_t child = firstChild;
            for (int o = 0; o < 8; ++o) {
                const std::uint64_t childBegin = runs[static_cast<std::size_t>(o)];
                const std::uint64_t childEnd = runs[static_cast<std::size_t>(o + 1)];
                if (childEnd == childBegin)
                    continue;
                build(child, cell.octantCell(o), childBegin, childEnd, level + 1, o);
                BuildNode& node = mNodes[nodeIndex]; // mNodes may have grown
                node.boundsMin = glm::min(node.boundsMin, mNodes[child].boundsMin);
                node.boundsMax = glm::max(node.boundsMax, mNodes[child].boundsMax);
                ++child;
            }
        }
        bake(nodeIndex, begin, end);
    }

    void bake(std::size_t nodeIndex, std::uint64_t subtreeBegin, std::uint64_t subtreeEnd) {
        const BuildNode& node = mNodes[nodeIndex];
        mBaker.reset(node.cellMin, node.cellMax);
        const bool hasChildren = node.childCount > 0;
        if (hasChildren && mParams.bakeInnerDirect) {
            mBaker.addTriangles(std::span(mTriangles).subspan(subtreeBegin, subtreeEnd - subtreeBegin));
            mNodes[nodeIndex].cube = mBaker.finish();
            return;
        }
        mBaker.addTriangles(std::span(mTriangles).subspan(node.firstTriangle, node.triangleCount));
        if (!hasChildren) {
            mNodes[nodeIndex].cube = mBaker.finish();
            return;
        }
        std::array<const ColorCube*, 8> children{};
        for (std::uint32_t c = 0; c < node.childCount; ++c) {
            const BuildNode& child = mNodes[node.firstChild + c];
            children[child.octant] = &child.cube;
        }
        const QuadrantColors underlay = compositeOctantQuadrants(children);
        mNodes[nodeIndex].cube = mBaker.finish(&underlay);
    }

    std::vector<storage::PackedTriangle>& mTriangles;
    const HierarchyParams& mParams;
    CubeBaker& mBaker;
    std::vector<BuildNode> mNodes;
};

} // namespace

Cell Cell::octantCell(int octant) const {
    const float half = 0.5f * size;
    return {min + glm::vec3((octant & 1) ? half : 0.0f, (octant & 2) ? half : 0.0f, (octant & 4) ? half : 0.0f), half};
}

int octantOf(const Cell& cell, const glm::vec3& point) {
    const glm::vec3 center = cell.min + glm::vec3(0.5f * cell.size);
    return (point.x < center.x ? 0 : 1) | (point.y < center.y ? 0 : 2) | (point.z < center.z ? 0 : 4);
}

glm::vec3 centroid(const storage::PackedTriangle& t) {
    return (toVec3(t.vertices[0].position) + toVec3(t.vertices[1].position) + toVec3(t.vertices[2].position)) /
           3.0f;
}

float extent(const storage::PackedTriangle& t) {
    glm::vec3 lo(std::numeric_limits<float>::infinity());
    glm::vec3 hi(-std::numeric_limits<float>::infinity());
    growBounds(lo, hi, t);
    const glm::vec3 size = hi - lo;
    return std::max({size.x, size.y, size.z});
}

void growBounds(glm::vec3& lo, glm::vec3& hi, const storage::PackedTriangle& t) {
    for (const storage::PackedVertex& v : t.vertices) {
        const glm::vec3 p = toVec3(v.position);
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
    }
}

std::vector<BuildNode> buildOctree(
        std::vector<storage::PackedTriangle>& triangles,
        const Cell& cell,
        int level,
        int octant,
        const HierarchyParams& params,
        CubeBaker& baker) {
    return OctreeRecursion(triangles, params, baker).run(cell, level, octant);
}

} // namespace ff::builder
