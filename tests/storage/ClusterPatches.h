#pragma once

// Synthetic clusters for the codec and page tests: grid patches with random normals and
// colours (the worst case for the vertex codec), and their encoding.

#include <ff/storage/ClusterCodec.h>
#include <ff/storage/VertexCodec.h>

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <random>
#include <vector>

namespace ff::storage::test {

inline std::uint32_t draw(std::mt19937& rng) {
    return static_cast<std::uint32_t>(rng());
}

inline constexpr std::array<float, 3> kLo = {-3.0f, 10.0f, 0.5f};
inline constexpr std::array<float, 3> kHi = {5.0f, 12.0f, 4.5f};

inline PositionGrid testGrid(int bits = kDefaultPositionGridBits) {
    auto grid = PositionGrid::covering(kLo, kHi, bits);
    EXPECT_TRUE(grid.isOk()) << grid.status().toString();
    return *grid;
}

/** A w x h patch of vertices `spacing` grid steps apart from `origin`, two triangles a quad. */
struct Patch {
    std::vector<ClusterVertex> vertices;
    std::vector<std::uint8_t> indices;
};

inline Patch makePatch(
        int w,
        int h,
        std::uint32_t spacing,
        std::array<std::uint32_t, 3> origin,
        std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
    Patch p;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            ClusterVertex v{};
            v.coordinate = {
                    origin[0] + static_cast<std::uint32_t>(x) * spacing,
                    origin[1] + static_cast<std::uint32_t>(y) * spacing,
                    origin[2] + (draw(rng) % 97)};
            v.normalOct = encodeOctNormal(unit(rng), unit(rng), unit(rng));
            v.color = {
                    static_cast<std::uint8_t>(draw(rng)),
                    static_cast<std::uint8_t>(draw(rng)),
                    static_cast<std::uint8_t>(draw(rng)),
                    255};
            p.vertices.push_back(v);
        }
    for (int y = 0; y + 1 < h; ++y)
        for (int x = 0; x + 1 < w; ++x) {
            const auto at = [&](int dx, int dy) {
                return static_cast<std::uint8_t>((y + dy) * w + x + dx);
            };
            p.indices.insert(
                    p.indices.end(), {at(0, 0), at(1, 0), at(1, 1), at(0, 0), at(1, 1), at(0, 1)});
        }
    return p;
}

inline std::vector<std::byte> encode(const Patch& p) {
    std::vector<std::byte> bytes(encodedClusterBound(p.vertices.size(), p.indices.size() / 3));
    const auto written = encodeCluster(p.vertices, p.indices, bytes);
    EXPECT_TRUE(written.isOk()) << written.status().toString();
    bytes.resize(written.isOk() ? *written : 0);
    return bytes;
}

} // namespace ff::storage::test
