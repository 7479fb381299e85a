#include <ff/builder/ClusterBuild.h>
#include <ff/storage/VertexCodec.h>

#include <meshoptimizer.h>

#include <algorithm>
#include <array>
#include <string>

namespace ff::builder {

static_assert(
        sizeof(storage::ClusterVertex) == 20, "no padding: vertices are merged by their bytes");

ClusterBuildStats& ClusterBuildStats::operator+=(const ClusterBuildStats& other) noexcept {
    clusters += other.clusters;
    trianglesIn += other.trianglesIn;
    trianglesKept += other.trianglesKept;
    trianglesUnlit += other.trianglesUnlit;
    uniqueVertices += other.uniqueVertices;
    clusterVertices += other.clusterVertices;
    encodedBytes += other.encodedBytes;
    wideClusters += other.wideClusters;
    points += other.points;
    return *this;
}

namespace {

/** Trims `out` to the cluster of `written` bytes just encoded at `start` and counts it. */
Status keepCluster(std::vector<std::byte>& out, std::size_t start, std::size_t written, ClusterBuildStats& stats) {
    out.resize(start + written);
    FF_ASSIGN_OR_RETURN(const storage::ClusterInfo info, storage::readClusterInfo(std::span(out).subspan(start)));
    ++stats.clusters;
    stats.clusterVertices += info.vertexCount;
    stats.encodedBytes += written;
    stats.wideClusters += info.widePositions ? 1 : 0;
    return Status::ok();
}

} // namespace

ClusterEncoder::ClusterEncoder(ClusterLimits limits)
    : mLimits(limits) {}

Result<std::size_t> ClusterEncoder::buildMeshlets(
        std::span<const storage::PackedTriangle> triangles,
        const storage::PositionGrid& grid,
        ClusterBuildStats& stats) {
    if (mLimits.maxVertices < 3 || mLimits.maxVertices > storage::kMaxClusterVertices ||
        mLimits.maxTriangles < 4 || mLimits.maxTriangles > storage::kMaxClusterTriangles ||
        mLimits.maxTriangles % 4 != 0)
        return Status(
                ErrorCode::InvalidArgument,
                "cluster limits must be 3-255 vertices and 4-512 triangles (a multiple of 4), "
                "not " + std::to_string(mLimits.maxVertices) +
                        " and " + std::to_string(mLimits.maxTriangles));
    stats.trianglesIn = triangles.size();
    mMeshlets.clear();
    if (triangles.empty())
        return std::size_t{0};

    // Every corner as the cluster will store it, so that vertices equal after quantization
    // (and after the normal's rounding to 12 bits) merge.
    mCorners.clear();
    for (const storage::PackedTriangle& t : triangles)
        for (const storage::PackedVertex& v : t.vertices)
            mCorners.push_back(
                    {grid.quantize(v.position),
                     storage::roundNormalTo12Bits(v.normalOct),
                     v.color});
    mRemap.resize(mCorners.size());
    const std::size_t unique = meshopt_generateVertexRemap(
            mRemap.data(),
            nullptr,
            mCorners.size(),
            mCorners.data(),
            mCorners.size(),
            sizeof(storage::ClusterVertex));
    mVertices.resize(unique);
    meshopt_remapVertexBuffer(
            mVertices.data(),
            mCorners.data(),
            mCorners.size(),
            sizeof(storage::ClusterVertex),
            mRemap.data());
    stats.uniqueVertices = unique;

    // Triangles whose corners fell onto fewer than three grid points draw nothing.
    mIndices.clear();
    for (std::size_t t = 0; t < triangles.size(); ++t) {
        const std::array<unsigned int, 3> corner = {
                mRemap[3 * t], mRemap[3 * t + 1], mRemap[3 * t + 2]};
        const auto& a = mVertices[corner[0]].coordinate;
        const auto& b = mVertices[corner[1]].coordinate;
        const auto& c = mVertices[corner[2]].coordinate;
        if (a == b || b == c || a == c)
            continue;
        mIndices.insert(mIndices.end(), corner.begin(), corner.end());
        if (std::all_of(corner.begin(), corner.end(), [&](unsigned int k) {
                return storage::isUnlitNormal(mVertices[k].normalOct);
            }))
            ++stats.trianglesUnlit;
    }
    stats.trianglesKept = mIndices.size() / 3;
    if (mIndices.empty())
        return std::size_t{0};

    meshopt_optimizeVertexCache(mIndices.data(), mIndices.data(), mIndices.size(), unique);
    mPositions.resize(unique * 3);
    for (std::size_t i = 0; i < unique; ++i) {
        const auto p = grid.position(mVertices[i].coordinate);
        std::copy(p.begin(), p.end(), mPositions.begin() + static_cast<std::ptrdiff_t>(3 * i));
    }
    const std::size_t maxMeshlets =
            meshopt_buildMeshletsBound(mIndices.size(), mLimits.maxVertices, mLimits.maxTriangles);
    std::vector<meshopt_Meshlet> meshlets(maxMeshlets);
    mMeshletVertices.resize(maxMeshlets * mLimits.maxVertices);
    mMeshletTriangles.resize(maxMeshlets * mLimits.maxTriangles * 3);
    const std::size_t count = meshopt_buildMeshlets(
            meshlets.data(),
            mMeshletVertices.data(),
            mMeshletTriangles.data(),
            mIndices.data(),
            mIndices.size(),
            mPositions.data(),
            unique,
            3 * sizeof(float),
            mLimits.maxVertices,
            mLimits.maxTriangles,
            0.0f);
    for (std::size_t m = 0; m < count; ++m)
        mMeshlets.push_back(
                {meshlets[m].vertex_offset,
                 meshlets[m].triangle_offset,
                 meshlets[m].vertex_count,
                 meshlets[m].triangle_count});
    return count;
}

Result<std::uint32_t> ClusterEncoder::countClusters(
        std::span<const storage::PackedTriangle> triangles, const storage::PositionGrid& grid) {
    ClusterBuildStats stats;
    FF_ASSIGN_OR_RETURN(const std::size_t count, buildMeshlets(triangles, grid, stats));
    return static_cast<std::uint32_t>(count);
}

Result<ClusterBuildStats> ClusterEncoder::encode(
        std::span<const storage::PackedTriangle> triangles,
        const storage::PositionGrid& grid,
        std::vector<std::byte>& out) {
    ClusterBuildStats stats;
    FF_ASSIGN_OR_RETURN(const std::size_t count, buildMeshlets(triangles, grid, stats));

    std::array<storage::ClusterVertex, storage::kMaxClusterVertices> local{};
    std::array<storage::ClusterVertex, storage::kMaxClusterVertices> ordered{};
    std::array<unsigned int, storage::kMaxClusterTriangles * 3> localIndices{};
    std::array<unsigned int, storage::kMaxClusterVertices> fetchRemap{};
    std::array<std::uint8_t, storage::kMaxClusterTriangles * 3> narrow{};
    for (std::size_t m = 0; m < count; ++m) {
        const Meshlet& meshlet = mMeshlets[m];
        for (std::size_t v = 0; v < meshlet.vertexCount; ++v)
            local[v] = mVertices[mMeshletVertices[meshlet.vertexOffset + v]];
        const std::size_t indexCount = std::size_t{meshlet.triangleCount} * 3;
        for (std::size_t i = 0; i < indexCount; ++i)
            localIndices[i] = mMeshletTriangles[meshlet.triangleOffset + i];
        // The index codec wants triangles in vertex-cache order and vertices in order of first
        // use: it then spends about a byte a triangle.
        meshopt_optimizeVertexCache(
                localIndices.data(), localIndices.data(), indexCount, meshlet.vertexCount);
        const std::size_t used = meshopt_optimizeVertexFetchRemap(
                fetchRemap.data(), localIndices.data(), indexCount, meshlet.vertexCount);
        meshopt_remapVertexBuffer(
                ordered.data(),
                local.data(),
                meshlet.vertexCount,
                sizeof(storage::ClusterVertex),
                fetchRemap.data());
        for (std::size_t i = 0; i < indexCount; ++i)
            narrow[i] = static_cast<std::uint8_t>(fetchRemap[localIndices[i]]);

        const std::size_t start = out.size();
        out.resize(start + storage::encodedClusterBound(used, meshlet.triangleCount));
        FF_ASSIGN_OR_RETURN(
                const std::size_t written,
                storage::encodeCluster(
                        std::span(ordered).first(used),
                        std::span(narrow).first(indexCount),
                        std::span(out).subspan(start)));
        FF_RETURN_IF_ERROR(keepCluster(out, start, written, stats));
    }
    return stats;
}

Result<ClusterBuildStats> ClusterEncoder::encodePoints(
        std::span<const storage::PackedVertex> points,
        const storage::PositionGrid& grid,
        std::vector<std::byte>& out) {
    ClusterBuildStats stats;
    if (points.empty())
        return stats;
    mPositions.resize(points.size() * 3);
    for (std::size_t i = 0; i < points.size(); ++i)
        for (std::size_t a = 0; a < 3; ++a)
            mPositions[3 * i + a] = points[i].position[a];
    mRemap.resize(points.size());
    meshopt_spatialSortRemap(mRemap.data(), mPositions.data(), points.size(), 3 * sizeof(float));
    mVertices.resize(points.size());
    for (std::size_t i = 0; i < points.size(); ++i) // mRemap: old index -> new position
        mVertices[mRemap[i]] = {grid.quantize(points[i].position), points[i].normalOct, points[i].color};
    for (std::size_t first = 0; first < points.size(); first += storage::kMaxClusterVertices) {
        const std::size_t count = std::min<std::size_t>(storage::kMaxClusterVertices, points.size() - first);
        const std::size_t start = out.size();
        out.resize(start + storage::encodedClusterBound(count, 0));
        FF_ASSIGN_OR_RETURN(
                const std::size_t written,
                storage::encodePointCluster(std::span(mVertices).subspan(first, count), std::span(out).subspan(start)));
        FF_RETURN_IF_ERROR(keepCluster(out, start, written, stats));
        stats.points += count;
    }
    return stats;
}

} // namespace ff::builder
