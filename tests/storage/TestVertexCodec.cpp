#include <ff/storage/VertexCodec.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

namespace ff::storage {
namespace {

using Vec3 = std::array<float, 3>;

double length(const Vec3& v) {
    return std::sqrt(double{v[0]} * v[0] + double{v[1]} * v[1] + double{v[2]} * v[2]);
}

/** Angle in radians between two directions (need not be unit). */
double angleBetween(const Vec3& a, const Vec3& b) {
    const double dot = double{a[0]} * b[0] + double{a[1]} * b[1] + double{a[2]} * b[2];
    return std::acos(std::clamp(dot / (length(a) * length(b)), -1.0, 1.0));
}

/** Directions covering the sphere evenly (Fibonacci lattice), plus axes and diagonals. */
std::vector<Vec3> testDirections() {
    std::vector<Vec3> dirs;
    constexpr int kCount = 4000;
    const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
    for (int i = 0; i < kCount; ++i) {
        const double z = 1.0 - 2.0 * (i + 0.5) / kCount;
        const double r = std::sqrt(1.0 - z * z);
        const double phi = golden * i;
        dirs.push_back(
                {static_cast<float>(r * std::cos(phi)),
                 static_cast<float>(r * std::sin(phi)),
                 static_cast<float>(z)});
    }
    for (int axis = 0; axis < 3; ++axis) {
        for (float sign : {-1.0f, 1.0f}) {
            Vec3 v{0.0f, 0.0f, 0.0f};
            v[static_cast<std::size_t>(axis)] = sign;
            dirs.push_back(v);
        }
    }
    for (float x : {-1.0f, 1.0f})
        for (float y : {-1.0f, 1.0f})
            for (float z : {-1.0f, 0.0f, 1.0f})
                dirs.push_back({x, y, z});
    // Just below the fold (z slightly negative) and on it.
    dirs.push_back({0.6f, 0.8f, -1e-7f});
    dirs.push_back({-0.6f, 0.8f, 0.0f});
    return dirs;
}

TEST(VertexCodecTest, OctNormalRoundTripIsAccurateEverywhere) {
    double worst = 0.0;
    for (const Vec3& d : testDirections()) {
        const Vec3 decoded = decodeOctNormal(encodeOctNormal(d[0], d[1], d[2]));
        EXPECT_NEAR(length(decoded), 1.0, 1e-6);
        worst = std::max(worst, angleBetween(d, decoded));
    }
    // snorm16 steps are 1/32767 in octahedral space: about 1e-4 rad in the worst place.
    EXPECT_LT(worst, 2e-4);
}

TEST(VertexCodecTest, AxesEncodeToTheOctahedronCorners) {
    using Oct = std::array<std::int16_t, 2>;
    EXPECT_EQ(encodeOctNormal(0, 0, 1), (Oct{0, 0}));
    EXPECT_EQ(encodeOctNormal(1, 0, 0), (Oct{32767, 0}));
    EXPECT_EQ(encodeOctNormal(-1, 0, 0), (Oct{-32767, 0}));
    EXPECT_EQ(encodeOctNormal(0, 1, 0), (Oct{0, 32767}));
    EXPECT_EQ(encodeOctNormal(0, -1, 0), (Oct{0, -32767}));
    const Oct minusZ = encodeOctNormal(0, 0, -1);
    EXPECT_EQ(std::abs(minusZ[0]), 32767);
    EXPECT_EQ(std::abs(minusZ[1]), 32767);
    const Vec3 back = decodeOctNormal(minusZ);
    EXPECT_NEAR(back[2], -1.0f, 1e-6f);
}

TEST(VertexCodecTest, EncodingIgnoresLength) {
    const std::vector<Vec3> dirs = testDirections();
    for (std::size_t i = 0; i < dirs.size(); i += 7) {
        const Vec3& d = dirs[i];
        const auto unit = encodeOctNormal(d[0], d[1], d[2]);
        const auto scaled = encodeOctNormal(d[0] * 7.5f, d[1] * 7.5f, d[2] * 7.5f);
        // Division by the scaled L1 norm may round differently by an ulp: one code at most.
        EXPECT_LE(std::abs(unit[0] - scaled[0]), 1) << i;
        EXPECT_LE(std::abs(unit[1] - scaled[1]), 1) << i;
    }
    EXPECT_EQ(encodeOctNormal(0.0f, 3.0f, 4.0f), encodeOctNormal(0.0f, 0.6f, 0.8f));
}

TEST(VertexCodecTest, DegenerateNormalsEncodePlusZ) {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();
    const std::array<Vec3, 6> degenerate = {{
            {0.0f, 0.0f, 0.0f},
            {-0.0f, 0.0f, -0.0f},
            {nan, 0.0f, 1.0f},
            {0.0f, nan, 0.0f},
            {inf, 0.0f, 0.0f},
            {1.0f, -inf, 0.0f},
    }};
    for (const Vec3& d : degenerate) {
        const auto oct = encodeOctNormal(d[0], d[1], d[2]);
        EXPECT_EQ(oct, (std::array<std::int16_t, 2>{0, 0}));
        const Vec3 v = decodeOctNormal(oct);
        EXPECT_EQ(v, (Vec3{0.0f, 0.0f, 1.0f}));
    }
}

TEST(VertexCodecTest, EveryCodeDecodesToAUnitVectorThatReEncodesNearby) {
    // Includes -32768, which snorm decoding clamps to -1.
    for (int a = -32768; a <= 32767; a += 257) {
        for (int b = -32768; b <= 32767; b += 263) {
            const std::array<std::int16_t, 2> oct = {
                    static_cast<std::int16_t>(a), static_cast<std::int16_t>(b)};
            const Vec3 v = decodeOctNormal(oct);
            ASSERT_TRUE(std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]));
            ASSERT_NEAR(length(v), 1.0, 1e-6) << a << " " << b;
            const Vec3 again = decodeOctNormal(encodeOctNormal(v[0], v[1], v[2]));
            ASSERT_LT(angleBetween(v, again), 2e-4) << a << " " << b;
        }
    }
    const Vec3 corner = decodeOctNormal({-32768, -32768});
    EXPECT_NEAR(corner[2], -1.0f, 1e-6f);
}

TEST(VertexCodecTest, SrgbTableEndpointsAndKnownValues) {
    EXPECT_EQ(srgb8ToLinear(0), 0.0f);
    EXPECT_EQ(srgb8ToLinear(255), 1.0f);
    EXPECT_NEAR(srgb8ToLinear(10), 10.0 / 255.0 / 12.92, 1e-7); // linear segment
    EXPECT_NEAR(srgb8ToLinear(11), std::pow((11.0 / 255.0 + 0.055) / 1.055, 2.4), 1e-7);
    EXPECT_NEAR(srgb8ToLinear(128), 0.2158605, 1e-6);
    EXPECT_NEAR(srgb8ToLinear(188), 0.5028865, 1e-6);
    for (int c = 1; c < 256; ++c)
        EXPECT_LT(
                srgb8ToLinear(static_cast<std::uint8_t>(c - 1)),
                srgb8ToLinear(static_cast<std::uint8_t>(c)));
}

TEST(VertexCodecTest, SrgbRoundTripIsExactForEveryCode) {
    for (int c = 0; c < 256; ++c) {
        const auto code = static_cast<std::uint8_t>(c);
        EXPECT_EQ(linearToSrgb8(srgb8ToLinear(code)), code) << c;
    }
}

TEST(VertexCodecTest, LinearToSrgbPicksTheNearestCodeInLinearSpace) {
    EXPECT_EQ(linearToSrgb8(0.5f), 188); // 0.5029 is closer than 187's 0.4969
    for (int c = 0; c < 255; ++c) {
        const float lo = srgb8ToLinear(static_cast<std::uint8_t>(c));
        const float hi = srgb8ToLinear(static_cast<std::uint8_t>(c + 1));
        const float mid = 0.5f * (lo + hi);
        EXPECT_EQ(linearToSrgb8(lo + 0.25f * (hi - lo)), c) << c;
        EXPECT_EQ(linearToSrgb8(hi - 0.25f * (hi - lo)), c + 1) << c;
        const std::uint8_t atMid = linearToSrgb8(mid);
        EXPECT_TRUE(atMid == c || atMid == c + 1) << c;
    }
}

TEST(VertexCodecTest, LinearToSrgbClampsOutOfRangeInput) {
    EXPECT_EQ(linearToSrgb8(-0.5f), 0);
    EXPECT_EQ(linearToSrgb8(-0.0f), 0);
    EXPECT_EQ(linearToSrgb8(1e-9f), 0);
    EXPECT_EQ(linearToSrgb8(1.0f), 255);
    EXPECT_EQ(linearToSrgb8(7.0f), 255);
    EXPECT_EQ(linearToSrgb8(std::numeric_limits<float>::infinity()), 255);
    EXPECT_EQ(linearToSrgb8(-std::numeric_limits<float>::infinity()), 0);
    EXPECT_EQ(linearToSrgb8(std::numeric_limits<float>::quiet_NaN()), 0);
}

TEST(VertexCodecTest, Unorm8RoundsToNearestAndClamps) {
    for (int k = 0; k < 256; ++k)
        EXPECT_EQ(toUnorm8(static_cast<float>(k) / 255.0f), k) << k;
    EXPECT_EQ(toUnorm8(0.5f), 128); // 127.5 rounds half away from zero
    EXPECT_EQ(toUnorm8(0.49f / 255.0f), 0);
    EXPECT_EQ(toUnorm8(0.51f / 255.0f), 1);
    EXPECT_EQ(toUnorm8(-1.0f), 0);
    EXPECT_EQ(toUnorm8(2.0f), 255);
    EXPECT_EQ(toUnorm8(std::numeric_limits<float>::infinity()), 255);
    EXPECT_EQ(toUnorm8(std::numeric_limits<float>::quiet_NaN()), 0);
}

} // namespace
} // namespace ff::storage
