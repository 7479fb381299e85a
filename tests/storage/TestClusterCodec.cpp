#include "ClusterPatches.h"

#include <ff/storage/ClusterCodec.h>
#include <ff/storage/VertexCodec.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace ff::storage {
namespace {

using test::draw;
using test::encode;
using test::kHi;
using test::kLo;
using test::makePatch;
using test::Patch;
using test::testGrid;

struct Decoded {
    std::vector<PackedVertex> vertices;
    std::vector<std::uint8_t> indices;
};

Result<Decoded> decode(std::span<const std::byte> bytes, const PositionGrid& grid) {
    FF_ASSIGN_OR_RETURN(const ClusterInfo info, readClusterInfo(bytes));
    Decoded d;
    d.vertices.resize(info.vertexCount);
    d.indices.resize(std::size_t{info.triangleCount} * 3);
    FF_RETURN_IF_ERROR(decodeCluster(bytes, grid, d.vertices, d.indices));
    return d;
}

/** Each triangle rotated to start at its smallest index: the index codec keeps the order and
 *  the winding of triangles, not which vertex comes first. */
std::vector<std::uint8_t> rotatedToSmallestFirst(std::vector<std::uint8_t> indices) {
    for (std::size_t t = 0; t + 2 < indices.size(); t += 3) {
        const auto first = std::min_element(
                indices.begin() + static_cast<std::ptrdiff_t>(t),
                indices.begin() + static_cast<std::ptrdiff_t>(t + 3));
        std::rotate(
                indices.begin() + static_cast<std::ptrdiff_t>(t),
                first,
                indices.begin() + static_cast<std::ptrdiff_t>(t + 3));
    }
    return indices;
}

void expectDecodesTo(const Patch& p, std::span<const std::byte> bytes, const PositionGrid& grid) {
    const auto d = decode(bytes, grid);
    ASSERT_TRUE(d.isOk()) << d.status().toString();
    ASSERT_EQ(d->vertices.size(), p.vertices.size());
    EXPECT_EQ(rotatedToSmallestFirst(d->indices), rotatedToSmallestFirst(p.indices));
    for (std::size_t i = 0; i < p.vertices.size(); ++i) {
        EXPECT_EQ(d->vertices[i].position, grid.position(p.vertices[i].coordinate))
                << "vertex " << i;
        EXPECT_EQ(d->vertices[i].normalOct, roundNormalTo12Bits(p.vertices[i].normalOct))
                << "vertex " << i;
        EXPECT_EQ(d->vertices[i].color, p.vertices[i].color) << "vertex " << i;
    }
}

TEST(ClusterCodecTest, ANarrowClusterRoundTripsToItsGridPositions) {
    const Patch p = makePatch(8, 8, 37, {1000, 2000, 3000}, 1);
    const auto bytes = encode(p);
    const auto info = readClusterInfo(bytes);
    ASSERT_TRUE(info.isOk()) << info.status().toString();
    EXPECT_EQ(info->vertexCount, 64u);
    EXPECT_EQ(info->triangleCount, 98u);
    EXPECT_EQ(info->encodedBytes, bytes.size());
    EXPECT_FALSE(info->widePositions);
    expectDecodesTo(p, bytes, testGrid());
    // What the codec is for: 64 vertices and 98 triangles in well under the 60 bytes a
    // triangle of format v1 (random normals and colours compress worst).
    EXPECT_LT(bytes.size(), 98u * 20u) << bytes.size() << " bytes";
}

TEST(ClusterCodecTest, AClusterSpanningMoreThan16BitsOfGridIsStoredWide) {
    const Patch p = makePatch(6, 5, 20000, {5, 70000, 1u << 23}, 2);
    const auto bytes = encode(p);
    const auto info = readClusterInfo(bytes);
    ASSERT_TRUE(info.isOk()) << info.status().toString();
    EXPECT_TRUE(info->widePositions);
    expectDecodesTo(p, bytes, testGrid(24));
}

TEST(ClusterCodecTest, TheSameInputGivesTheSameBytes) {
    const Patch p = makePatch(9, 7, 11, {0, 0, 0}, 3);
    EXPECT_EQ(encode(p), encode(p));
}

// Two clusters that share an edge decode its vertices to the same floats whatever their
// storage (narrow deltas from different bases, or wide): neighbouring clusters never crack.
TEST(ClusterCodecTest, AVertexTwoClustersShareDecodesToOneFloat) {
    const PositionGrid grid = testGrid(24);
    const Patch left = makePatch(5, 5, 301, {123456, 654321, 777}, 4);
    Patch right = makePatch(5, 5, 301, {123456 + 4 * 301, 654321, 777}, 5);
    Patch wide = makePatch(5, 5, 30001, {123456 + 4 * 301 - 4 * 30001, 654321, 777}, 6);
    for (int y = 0; y < 5; ++y) { // right's first column and wide's last are left's last
        right.vertices[static_cast<std::size_t>(y * 5)].coordinate =
                left.vertices[static_cast<std::size_t>(y * 5 + 4)].coordinate;
        wide.vertices[static_cast<std::size_t>(y * 5 + 4)].coordinate =
                left.vertices[static_cast<std::size_t>(y * 5 + 4)].coordinate;
    }
    const auto a = decode(encode(left), grid);
    const auto b = decode(encode(right), grid);
    const auto c = decode(encode(wide), grid);
    ASSERT_TRUE(a.isOk() && b.isOk() && c.isOk());
    ASSERT_TRUE(readClusterInfo(encode(wide))->widePositions);
    for (std::size_t y = 0; y < 5; ++y) {
        EXPECT_EQ(a->vertices[y * 5 + 4].position, b->vertices[y * 5].position);
        EXPECT_EQ(a->vertices[y * 5 + 4].position, c->vertices[y * 5 + 4].position);
    }
}

TEST(ClusterCodecTest, QuantizedPositionsStayWithinTheStatedErrorBound) {
    for (const int bits : {8, 16, 20, 24, 28}) {
        const PositionGrid grid = testGrid(bits);
        std::mt19937 rng(static_cast<std::uint32_t>(bits));
        float worst = 0.0f;
        for (int i = 0; i < 20000; ++i) {
            std::array<float, 3> p{};
            for (std::size_t a = 0; a < 3; ++a)
                p[a] = std::uniform_real_distribution<float>(kLo[a], kHi[a])(rng);
            if (i < 8) { // the corners
                for (std::size_t a = 0; a < 3; ++a)
                    p[a] = (i >> a & 1) ? kHi[a] : kLo[a];
            }
            const auto back = grid.position(grid.quantize(p));
            for (std::size_t a = 0; a < 3; ++a)
                worst = std::max(worst, std::fabs(back[a] - p[a]));
        }
        EXPECT_LE(worst, grid.maxError()) << bits << " bits";
        // 8 units of extent: at 20 bits the bound is about 4 µ-units.
        if (bits == kDefaultPositionGridBits) {
            EXPECT_LT(grid.maxError(), 8.0f / (1 << 20));
        }
    }
}

// A precision target in scene units, whatever the extent: a 10^9-triangle terrain (~45 k units
// of 1-unit triangles) on a step of 1/1000 needs 26 bits, and stays within half a step plus the
// float rounding of positions that large; a vertex shared by a narrow and a wide cluster there
// decodes to one float.
TEST(ClusterCodecTest, AGridOfAGivenStepCoversALargeExtentAtThatPrecision) {
    const std::array<float, 3> lo = {-22360.0f, -50.0f, -22360.0f};
    const std::array<float, 3> hi = {22360.0f, 400.0f, 22360.0f};
    const auto grid = PositionGrid::withStep(lo, hi, 0.001f);
    ASSERT_TRUE(grid.isOk()) << grid.status().toString();
    EXPECT_EQ(grid->bits, 26);
    // Half the step, and half a float ulp at the grid's farthest decodable position (the grid is a
    // cube of 2^26 steps: ~67 k units out on the y axis; 0.004).
    EXPECT_LT(grid->maxError(), 0.005f);
    std::mt19937 rng(12);
    float worst = 0.0f;
    for (int i = 0; i < 20000; ++i) {
        std::array<float, 3> p{};
        for (std::size_t a = 0; a < 3; ++a)
            p[a] = std::uniform_real_distribution<float>(lo[a], hi[a])(rng);
        const auto back = grid->position(grid->quantize(p));
        for (std::size_t a = 0; a < 3; ++a)
            worst = std::max(worst, std::fabs(back[a] - p[a]));
    }
    EXPECT_LE(worst, grid->maxError());
    const std::array<std::uint32_t, 3> far = grid->quantize({22000.5f, 12.25f, -21000.75f});
    Patch narrow = makePatch(4, 4, 900, {far[0] - 2700, far[1], far[2] - 2700}, 13);
    Patch wide = makePatch(4, 4, 40000, {far[0] - 120000, far[1], far[2] - 120000}, 14);
    narrow.vertices[15].coordinate = far;
    wide.vertices[15].coordinate = far;
    ASSERT_FALSE(readClusterInfo(encode(narrow))->widePositions);
    ASSERT_TRUE(readClusterInfo(encode(wide))->widePositions);
    const auto a = decode(encode(narrow), *grid);
    const auto b = decode(encode(wide), *grid);
    ASSERT_TRUE(a.isOk() && b.isOk());
    EXPECT_EQ(a->vertices[15].position, b->vertices[15].position);
    EXPECT_FALSE(PositionGrid::withStep(lo, hi, 1e-6f).isOk()); // 45 G steps: past 31 bits
    EXPECT_FALSE(PositionGrid::withStep(lo, hi, 0.0f).isOk());
}

// 12-bit octahedral normals: at most 0.062 degrees off over this sweep of the sphere (measured;
// through snorm16 first, as the builder has them), where the same sweep straight from the
// float directions gives 0.058 for 12 bits, 0.23 for 10 and 0.92 for 8. The unlit code
// (KHR_materials_unlit) survives.
TEST(ClusterCodecTest, TwelveBitNormalsStayWithinATenthOfADegree) {
    double worst = 0.0;
    for (int i = 0; i < 200; ++i)
        for (int j = 0; j < 400; ++j) {
            const double theta = M_PI * (i + 0.5) / 200.0;
            const double phi = 2.0 * M_PI * j / 400.0;
            const std::array<float, 3> n = {
                    static_cast<float>(std::sin(theta) * std::cos(phi)),
                    static_cast<float>(std::sin(theta) * std::sin(phi)),
                    static_cast<float>(std::cos(theta))};
            const auto back =
                    decodeOctNormal(roundNormalTo12Bits(encodeOctNormal(n[0], n[1], n[2])));
            const double dot = std::clamp(
                    double{back[0]} * n[0] + double{back[1]} * n[1] + double{back[2]} * n[2],
                    -1.0,
                    1.0);
            worst = std::max(worst, std::acos(dot) * 180.0 / M_PI);
        }
    EXPECT_LT(worst, 0.07) << worst << " degrees";
    EXPECT_EQ(roundNormalTo12Bits(kUnlitNormalOct), kUnlitNormalOct);
    EXPECT_EQ(roundNormalTo12Bits({32767, -32767}), (std::array<std::int16_t, 2>{32767, -32767}));
}

TEST(ClusterCodecTest, TheEncoderRefusesClustersOutsideItsLimits) {
    std::vector<std::byte> out(1 << 16);
    const Patch p = makePatch(4, 4, 1, {0, 0, 0}, 7);
    EXPECT_FALSE(encodeCluster({}, p.indices, out).isOk());
    EXPECT_FALSE(encodeCluster(p.vertices, {}, out).isOk()); // points are encodePointCluster's
    EXPECT_FALSE(encodePointCluster({}, out).isOk());
    std::vector<std::uint8_t> badIndex = p.indices;
    badIndex[4] = 16;
    EXPECT_FALSE(encodeCluster(p.vertices, badIndex, out).isOk());
    std::vector<std::uint8_t> notTriangles(p.indices.begin(), p.indices.end() - 1);
    EXPECT_FALSE(encodeCluster(p.vertices, notTriangles, out).isOk());
    Patch huge = p;
    huge.vertices[3].coordinate[1] = 1u << 31;
    EXPECT_FALSE(encodeCluster(huge.vertices, huge.indices, out).isOk());
    std::vector<std::byte> small(8);
    EXPECT_FALSE(encodeCluster(p.vertices, p.indices, small).isOk());
    const Patch tooMany = makePatch(16, 16, 1, {0, 0, 0}, 8); // 256 vertices
    EXPECT_FALSE(encodeCluster(tooMany.vertices, std::span(tooMany.indices).first(3), out).isOk());
}

// Splats: a cluster of vertices alone, no index stream, flagged so (FORMAT.md §6.3).
TEST(ClusterCodecTest, APointClusterRoundTripsWithoutAnIndexStream) {
    const Patch p = makePatch(15, 17, 53, {1000, 2000, 3000}, 21); // 255 vertices, the most
    std::vector<std::byte> bytes(encodedClusterBound(p.vertices.size(), 0));
    const auto written = encodePointCluster(p.vertices, bytes);
    ASSERT_TRUE(written.isOk()) << written.status().toString();
    bytes.resize(*written);
    const auto info = readClusterInfo(bytes);
    ASSERT_TRUE(info.isOk()) << info.status().toString();
    EXPECT_TRUE(info->points());
    EXPECT_EQ(info->vertexCount, 255u);
    EXPECT_EQ(info->triangleCount, 0u);
    EXPECT_EQ(info->encodedBytes, bytes.size());
    expectDecodesTo(Patch{p.vertices, {}}, bytes, testGrid());
    // A triangle cluster's header never reads as points, nor the other way round.
    EXPECT_FALSE(readClusterInfo(encode(makePatch(4, 4, 1, {0, 0, 0}, 22)))->points());
}

TEST(ClusterCodecTest, APointClusterWithTrianglesOrAnIndexStreamIsRefused) {
    const Patch p = makePatch(8, 8, 37, {1000, 2000, 3000}, 23);
    std::vector<std::byte> points(encodedClusterBound(p.vertices.size(), 0));
    points.resize(*encodePointCluster(p.vertices, points));
    std::vector<std::byte> withTriangles = points;
    withTriangles[2] = std::byte{1}; // triangleCount 1 with the points flag
    EXPECT_FALSE(readClusterInfo(withTriangles).isOk());
    std::vector<std::byte> withIndexStream = points;
    withIndexStream[6] = std::byte{4}; // indexStreamBytes
    withIndexStream.resize(withIndexStream.size() + 4, std::byte{0xe1});
    EXPECT_FALSE(readClusterInfo(withIndexStream).isOk());
    std::vector<std::byte> triangles = encode(p);
    triangles[1] |= std::byte{2}; // the points flag on a cluster of triangles
    EXPECT_FALSE(readClusterInfo(triangles).isOk());
    for (std::size_t n = 0; n < points.size(); ++n) {
        const std::span<const std::byte> prefix(points.data(), n);
        std::vector<PackedVertex> v(kMaxClusterVertices);
        std::vector<std::uint8_t> idx;
        EXPECT_FALSE(decodeCluster(prefix, testGrid(), v, idx).isOk()) << n;
    }
}

// Every reader of the new bytes is memory-safe: every prefix is refused, and random bit flips
// either decode to vertices inside the grid and indices inside the cluster, or are refused.
TEST(ClusterCodecTest, EveryTruncationIsRefused) {
    const auto bytes = encode(makePatch(8, 8, 37, {1000, 2000, 3000}, 9));
    const PositionGrid grid = testGrid();
    for (std::size_t n = 0; n < bytes.size(); ++n) {
        const std::span<const std::byte> prefix(bytes.data(), n);
        EXPECT_FALSE(readClusterInfo(prefix).isOk()) << n;
        std::vector<PackedVertex> v(kMaxClusterVertices);
        std::vector<std::uint8_t> idx(kMaxClusterTriangles * 3);
        EXPECT_FALSE(decodeCluster(prefix, grid, v, idx).isOk()) << n;
    }
}

TEST(ClusterCodecTest, BitFlipsAndGarbageNeverDecodeOutOfRange) {
    const auto clean = encode(makePatch(8, 8, 37, {1000, 2000, 3000}, 10));
    const PositionGrid grid = testGrid();
    std::mt19937 rng(11);
    std::vector<PackedVertex> v(kMaxClusterVertices);
    std::vector<std::uint8_t> idx(kMaxClusterTriangles * 3);
    int refused = 0;
    for (int trial = 0; trial < 4000; ++trial) {
        std::vector<std::byte> bytes = clean;
        if (trial % 4 == 3) { // garbage of any length after a plausible header
            bytes.resize(draw(rng) % 1200);
            for (auto& b : bytes)
                b = static_cast<std::byte>(draw(rng));
        } else {
            for (int f = 0, flips = 1 + static_cast<int>(draw(rng) % 4); f < flips; ++f)
                bytes[draw(rng) % bytes.size()] ^= static_cast<std::byte>(1u << (draw(rng) % 8));
        }
        const auto info = readClusterInfo(bytes);
        if (!info.isOk() || !decodeCluster(bytes, grid, v, idx).isOk()) {
            ++refused;
            continue;
        }
        ASSERT_LE(info->encodedBytes, bytes.size());
        for (std::size_t i = 0; i < std::size_t{info->triangleCount} * 3; ++i)
            ASSERT_LT(idx[i], info->vertexCount);
        for (std::uint32_t i = 0; i < info->vertexCount; ++i)
            for (std::size_t a = 0; a < 3; ++a)
                ASSERT_TRUE(std::isfinite(v[i].position[a]));
    }
    EXPECT_GT(refused, 1000); // the checks do refuse: at least the garbage
}

TEST(ClusterCodecTest, AGridNeedsFiniteBoundsAndBitsItCanHold) {
    EXPECT_FALSE(PositionGrid::covering(kLo, kHi, 0).isOk());
    EXPECT_FALSE(PositionGrid::covering(kLo, kHi, 32).isOk());
    EXPECT_TRUE(PositionGrid::covering(kLo, kHi, 31).isOk());
    EXPECT_FALSE(PositionGrid::covering({0, 0, NAN}, kHi).isOk());
    EXPECT_FALSE(PositionGrid::covering(kHi, kLo).isOk());
    const auto flat = PositionGrid::covering({1, 1, 1}, {1, 1, 1});
    ASSERT_TRUE(flat.isOk());
    EXPECT_EQ(flat->position(flat->quantize({1, 1, 1})), (std::array<float, 3>{1, 1, 1}));
}

} // namespace
} // namespace ff::storage
