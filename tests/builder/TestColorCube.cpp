// Color cubes against hand-computed values: baking of triangles and boxes, the compositing of
// Chamberlain et al. '96 Fig. 3 (front over back, then the average of four quadrants), and the
// unorm8 quantisation of premultiplied faces.

#include <ff/builder/ColorCube.h>
#include <ff/builder/SceneSink.h>
#include <ff/storage/ShadingModel.h>
#include <ff/storage/VertexCodec.h>

#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

namespace ff::builder {
namespace {

constexpr int kFaceMinusX = 0;
constexpr int kFacePlusX = 1;
constexpr int kFaceMinusY = 2;
constexpr int kFacePlusY = 3;
constexpr int kFaceMinusZ = 4;
constexpr int kFacePlusZ = 5;

// Sums of up to 64 samples in float: a few ulps, far below one unorm8 step.
constexpr float kSumTolerance = 1e-6f;

SourceVertex vertex(float x, float y, float z, const glm::vec3& normal, const glm::vec3& color) {
    return {glm::vec3(x, y, z), normal, glm::vec4(color, 1.0f)};
}

/** The quad [x0,x1] x [y0,y1] at height z, facing +Z, as two triangles. */
std::vector<storage::PackedTriangle>
quadZ(float x0, float x1, float y0, float y1, float z, const glm::vec3& color) {
    const glm::vec3 n(0.0f, 0.0f, 1.0f);
    const SourceVertex a = vertex(x0, y0, z, n, color);
    const SourceVertex b = vertex(x1, y0, z, n, color);
    const SourceVertex c = vertex(x1, y1, z, n, color);
    const SourceVertex d = vertex(x0, y1, z, n, color);
    return {packTriangle(a, b, c), packTriangle(a, c, d)};
}

/** The colour the baker must give a packed vertex: its stored sRGB colour, linearised, times the
 *  shading factor of its stored normal. */
glm::vec3 shadedColor(const storage::PackedVertex& v) {
    const auto n = storage::decodeOctNormal(v.normalOct);
    const float light = storage::shadingFactor(n[0], n[1], n[2]);
    return glm::vec3(
                   storage::srgb8ToLinear(v.color[0]),
                   storage::srgb8ToLinear(v.color[1]),
                   storage::srgb8ToLinear(v.color[2])) *
           light;
}

void expectFaceNear(
        const ColorCube& cube,
        int face,
        const glm::vec4& expected,
        float tolerance = kSumTolerance) {
    const glm::vec4& got = cube.faces[static_cast<std::size_t>(face)];
    for (int k = 0; k < 4; ++k)
        EXPECT_NEAR(got[k], expected[k], tolerance) << "face " << face << " channel " << k;
}

void expectFaceEq(const ColorCube& cube, int face, const glm::vec4& expected) {
    const glm::vec4& got = cube.faces[static_cast<std::size_t>(face)];
    for (int k = 0; k < 4; ++k)
        EXPECT_EQ(got[k], expected[k]) << "face " << face << " channel " << k;
}

ColorCube uniformCube(const glm::vec4& color) {
    ColorCube cube;
    cube.faces.fill(color);
    return cube;
}

/** Distinct opaque colours per face, so a test can tell which face of a box a sample saw. */
ColorCube distinctOpaqueCube() {
    ColorCube cube;
    for (int f = 0; f < storage::kCubeFaceCount; ++f)
        cube.faces[static_cast<std::size_t>(f)] =
                glm::vec4(0.125f * static_cast<float>(f + 1), 0.25f, 0.5f, 1.0f);
    return cube;
}

// ---- baking triangles ------------------------------------------------------------------------

TEST(CubeBakerTest, FullyCoveringQuadIsOpaqueOnItsFacesAndInvisibleEdgeOn) {
    CubeBaker baker(8);
    baker.reset(glm::vec3(0.0f), glm::vec3(1.0f));
    const std::vector<storage::PackedTriangle> quad =
            quadZ(0.0f, 1.0f, 0.0f, 1.0f, 0.5f, {0.8f, 0.4f, 0.2f});
    baker.addTriangles(quad);
    EXPECT_EQ(baker.coveredSamples(kFaceMinusZ), 64);
    EXPECT_EQ(baker.coveredSamples(kFacePlusZ), 64);
    const ColorCube cube = baker.finish();

    const glm::vec3 shaded = shadedColor(quad[0].vertices[0]);
    // Hand check of the shading model for the +Z normal: ambient + diffuse * L.z.
    EXPECT_NEAR(
            shaded.r,
            storage::srgb8ToLinear(storage::linearToSrgb8(0.8f)) *
                    (storage::kAmbient + storage::kDiffuse * storage::kLightDirection[2]),
            1e-6f);
    for (int face : {kFaceMinusZ, kFacePlusZ}) {
        EXPECT_EQ(cube.faces[static_cast<std::size_t>(face)].a, 1.0f) << "face " << face;
        expectFaceNear(cube, face, glm::vec4(shaded, 1.0f));
    }
    for (int face : {kFaceMinusX, kFacePlusX, kFaceMinusY, kFacePlusY}) {
        EXPECT_EQ(baker.coveredSamples(face), 0);
        expectFaceEq(cube, face, glm::vec4(0.0f));
    }
}

TEST(CubeBakerTest, QuadOverHalfTheFaceGivesHalfAlphaAndHalfPremultipliedColor) {
    CubeBaker baker(8);
    baker.reset(glm::vec3(0.0f), glm::vec3(1.0f));
    const std::vector<storage::PackedTriangle> quad =
            quadZ(0.0f, 0.5f, 0.0f, 1.0f, 0.25f, {0.3f, 0.6f, 0.9f});
    baker.addTriangles(quad);
    const ColorCube cube = baker.finish();
    const glm::vec3 shaded = shadedColor(quad[0].vertices[0]);
    for (int face : {kFaceMinusZ, kFacePlusZ}) {
        EXPECT_EQ(baker.coveredSamples(face), 32);
        EXPECT_EQ(cube.faces[static_cast<std::size_t>(face)].a, 0.5f);
        expectFaceNear(cube, face, glm::vec4(0.5f * shaded, 0.5f));
    }
}

TEST(CubeBakerTest, NearestSurfaceWinsPerFace) {
    CubeBaker baker(4);
    baker.reset(glm::vec3(0.0f), glm::vec3(1.0f));
    const std::vector<storage::PackedTriangle> low =
            quadZ(0.0f, 1.0f, 0.0f, 1.0f, 0.25f, {1.0f, 0.0f, 0.0f});
    const std::vector<storage::PackedTriangle> high =
            quadZ(0.0f, 1.0f, 0.0f, 1.0f, 0.75f, {0.0f, 0.0f, 1.0f});
    baker.addTriangles(high);
    baker.addTriangles(low);
    const ColorCube cube = baker.finish();
    // The viewer of -Z sees the low quad, the viewer of +Z the high one.
    expectFaceNear(cube, kFaceMinusZ, glm::vec4(shadedColor(low[0].vertices[0]), 1.0f));
    expectFaceNear(cube, kFacePlusZ, glm::vec4(shadedColor(high[0].vertices[0]), 1.0f));
}

TEST(CubeBakerTest, ResetForgetsThePreviousCell) {
    CubeBaker baker(8);
    baker.reset(glm::vec3(0.0f), glm::vec3(1.0f));
    baker.addTriangles(quadZ(0.0f, 1.0f, 0.0f, 1.0f, 0.5f, {1.0f, 1.0f, 1.0f}));
    baker.addBox(glm::mat4(1.0f), glm::vec3(0.25f), glm::vec3(0.75f), uniformCube(glm::vec4(1.0f)));
    baker.reset(glm::vec3(0.0f), glm::vec3(1.0f));
    const ColorCube cube = baker.finish();
    for (int face = 0; face < storage::kCubeFaceCount; ++face) {
        EXPECT_EQ(baker.coveredSamples(face), 0);
        expectFaceEq(cube, face, glm::vec4(0.0f));
    }
}

// ---- compositing (Fig. 3) --------------------------------------------------------------------

TEST(CompositeOctantsTest, OverIsPremultipliedPorterDuff) {
    const glm::vec4 front(0.25f, 0.125f, 0.0f, 0.5f);
    const glm::vec4 back(0.5f, 0.5f, 0.5f, 1.0f);
    const glm::vec4 result = over(front, back);
    EXPECT_EQ(result, glm::vec4(0.5f, 0.375f, 0.25f, 1.0f));
}

// Child 0 (x-, y-, z-) with a behind child 4 (x-, y-, z+): the +Z viewer sees 4 over 0, the -Z
// viewer 0 over 4, the X and Y viewers see them side by side in different quadrants.
TEST(CompositeOctantsTest, StackedChildrenCompositeFrontOverBackThenAverageQuadrants) {
    ColorCube below; // child 0
    ColorCube above; // child 4
    for (int f = 0; f < storage::kCubeFaceCount; ++f) {
        below.faces[static_cast<std::size_t>(f)] = glm::vec4(0.5f, 0.5f, 0.5f, 1.0f);
        above.faces[static_cast<std::size_t>(f)] = glm::vec4(0.25f, 0.125f, 0.0f, 0.5f);
    }
    below.faces[kFacePlusX] = glm::vec4(0.0f, 0.25f, 0.0f, 0.25f);
    above.faces[kFacePlusX] = glm::vec4(0.5f, 0.0f, 0.0f, 0.75f);
    std::array<const ColorCube*, 8> children{};
    children[0] = &below;
    children[4] = &above;

    const QuadrantColors quadrants = compositeOctantQuadrants(children);
    const ColorCube cube = compositeOctants(children);

    // +Z: quadrant (x-, y-) = above over below = (0.25 + 0.5*0.5, 0.125 + 0.5*0.5, 0 + 0.5*0.5,
    // 0.5 + 0.5*1); the three other quadrants are empty.
    EXPECT_EQ(quadrants[kFacePlusZ][0], glm::vec4(0.5f, 0.375f, 0.25f, 1.0f));
    for (std::size_t q = 1; q < 4; ++q)
        EXPECT_EQ(quadrants[kFacePlusZ][q], glm::vec4(0.0f));
    expectFaceEq(cube, kFacePlusZ, glm::vec4(0.125f, 0.09375f, 0.0625f, 0.25f));

    // -Z: the viewer sees the opaque lower child first, which hides the upper one.
    EXPECT_EQ(quadrants[kFaceMinusZ][0], glm::vec4(0.5f, 0.5f, 0.5f, 1.0f));
    expectFaceEq(cube, kFaceMinusZ, glm::vec4(0.125f, 0.125f, 0.125f, 0.25f));

    // +X: u = y, v = z. Quadrant (y-, z-) holds child 0 behind the empty child 1, quadrant
    // (y-, z+) child 4 behind the empty child 5.
    EXPECT_EQ(quadrants[kFacePlusX][0], below.faces[kFacePlusX]);
    EXPECT_EQ(quadrants[kFacePlusX][2], above.faces[kFacePlusX]);
    EXPECT_EQ(quadrants[kFacePlusX][1], glm::vec4(0.0f));
    EXPECT_EQ(quadrants[kFacePlusX][3], glm::vec4(0.0f));
    expectFaceEq(cube, kFacePlusX, glm::vec4(0.125f, 0.0625f, 0.0f, 0.25f));

    // -Y: u = z, v = x. Children 0 and 4 are the front ones (y-): quadrants (z-, x-), (z+, x-).
    EXPECT_EQ(quadrants[kFaceMinusY][0], below.faces[kFaceMinusY]);
    EXPECT_EQ(quadrants[kFaceMinusY][1], above.faces[kFaceMinusY]);
    expectFaceEq(cube, kFaceMinusY, glm::vec4(0.1875f, 0.15625f, 0.125f, 0.375f));
}

TEST(CompositeOctantsTest, NoChildrenIsTransparent) {
    const std::array<const ColorCube*, 8> children{};
    const ColorCube cube = compositeOctants(children);
    for (int face = 0; face < storage::kCubeFaceCount; ++face)
        expectFaceEq(cube, face, glm::vec4(0.0f));
}

TEST(CompositeOctantsTest, EightOpaqueChildrenGiveTheFrontLayer) {
    std::array<ColorCube, 8> cubes;
    std::array<const ColorCube*, 8> children{};
    for (std::size_t o = 0; o < 8; ++o) {
        cubes[o] = uniformCube(glm::vec4(0.0625f * static_cast<float>(o + 1), 0.0f, 0.0f, 1.0f));
        children[o] = &cubes[o];
    }
    const ColorCube cube = compositeOctants(children);
    // +Z sees octants 4..7: red = 0.0625 * (5+6+7+8) / 4.
    expectFaceEq(cube, kFacePlusZ, glm::vec4(0.40625f, 0.0f, 0.0f, 1.0f));
    // -X sees octants 0, 2, 4, 6: 0.0625 * (1+3+5+7) / 4.
    expectFaceEq(cube, kFaceMinusX, glm::vec4(0.25f, 0.0f, 0.0f, 1.0f));
}

// ---- quantisation ----------------------------------------------------------------------------

TEST(QuantizeCubeTest, ColorNeverExceedsAlpha) {
    ColorCube cube;
    // Rounding alone would give red 128 > alpha 127.
    cube.faces[0] = glm::vec4(0.5f, 0.3f, 0.1f, 0.499f);
    cube.faces[1] = glm::vec4(1.0f, 1.0f, 1.0f, 1.0f);
    cube.faces[2] = glm::vec4(0.0f);
    cube.faces[3] = glm::vec4(0.2f, 0.2f, 0.2f, 0.2f);
    cube.faces[4] = glm::vec4(0.0019f, 0.0f, 0.0f, 0.0019f); // rounds to alpha 0
    cube.faces[5] = glm::vec4(2.0f, -1.0f, 0.5f, 0.5f);      // out of range: clamped
    const auto bytes = quantizeCube(cube);
    using storage::toUnorm8;
    EXPECT_EQ(toUnorm8(0.5f), 128); // the case the clamp is for
    EXPECT_EQ(toUnorm8(0.499f), 127);
    EXPECT_EQ(bytes[0], (std::array<std::uint8_t, 4>{127, toUnorm8(0.3f), toUnorm8(0.1f), 127}));
    EXPECT_EQ(bytes[1], (std::array<std::uint8_t, 4>{255, 255, 255, 255}));
    EXPECT_EQ(bytes[2], (std::array<std::uint8_t, 4>{0, 0, 0, 0}));
    EXPECT_EQ(bytes[3], (std::array<std::uint8_t, 4>{51, 51, 51, 51}));
    EXPECT_EQ(bytes[4], (std::array<std::uint8_t, 4>{0, 0, 0, 0}));
    EXPECT_EQ(bytes[5], (std::array<std::uint8_t, 4>{128, 0, 128, 128}));

    // Every premultiplied colour (c <= a) on a fine grid keeps c <= a after rounding.
    for (int a = 0; a <= 64; ++a) {
        for (int c = 0; c <= a; ++c) {
            ColorCube grid;
            const float alpha = static_cast<float>(a) / 64.0f;
            const float color = static_cast<float>(c) / 64.0f * alpha + 0.001f;
            grid.faces.fill(glm::vec4(color, color, color, alpha));
            for (const auto& face : quantizeCube(grid))
                for (int k = 0; k < 3; ++k)
                    EXPECT_LE(face[static_cast<std::size_t>(k)], face[3]);
        }
    }
}

TEST(QuantizeCubeTest, DequantizeInvertsQuantize) {
    ColorCube cube;
    cube.faces.fill(glm::vec4(0.25f, 0.5f, 0.125f, 0.75f));
    const auto bytes = quantizeCube(cube);
    EXPECT_EQ(quantizeCube(dequantizeCube(bytes)), bytes);
    expectFaceNear(dequantizeCube(bytes), 0, glm::vec4(64.0f, 128.0f, 32.0f, 191.0f) / 255.0f);
}

// ---- baking boxes (instance level) -----------------------------------------------------------

TEST(CubeBakerTest, AxisAlignedBoxCoversItsProjectedArea) {
    CubeBaker baker(8);
    baker.reset(glm::vec3(0.0f), glm::vec3(1.0f));
    const ColorCube box = distinctOpaqueCube();
    // [0.25, 0.75] on each axis covers samples 2..5 of 8 per axis: 16 of 64.
    baker.addBox(glm::mat4(1.0f), glm::vec3(0.25f), glm::vec3(0.75f), box);
    const ColorCube cube = baker.finish();
    for (int face = 0; face < storage::kCubeFaceCount; ++face) {
        EXPECT_EQ(cube.faces[static_cast<std::size_t>(face)].a, 0.25f) << "face " << face;
        // Each viewer sees the box face that looks its way (same index), and only that one.
        expectFaceNear(cube, face, 0.25f * box.faces[static_cast<std::size_t>(face)]);
    }
    // Boxes are not triangles.
    for (int face = 0; face < storage::kCubeFaceCount; ++face)
        EXPECT_EQ(baker.coveredSamples(face), 0);
}

TEST(CubeBakerTest, TranslucentBoxesCompositeFrontToBack) {
    CubeBaker baker(4);
    baker.reset(glm::vec3(0.0f), glm::vec3(1.0f));
    const glm::vec4 nearColor(0.25f, 0.0f, 0.0f, 0.5f);
    const glm::vec4 farColor(0.0f, 0.5f, 0.0f, 1.0f);
    // Two slabs covering the whole XY face, one above the other.
    baker.addBox(
            glm::mat4(1.0f),
            glm::vec3(0.0f, 0.0f, 0.5f),
            glm::vec3(1.0f, 1.0f, 1.0f),
            uniformCube(nearColor));
    baker.addBox(
            glm::mat4(1.0f),
            glm::vec3(0.0f, 0.0f, 0.0f),
            glm::vec3(1.0f, 1.0f, 0.5f),
            uniformCube(farColor));
    const ColorCube cube = baker.finish();
    expectFaceNear(cube, kFacePlusZ, over(nearColor, farColor));
    expectFaceNear(cube, kFaceMinusZ, over(farColor, nearColor));
}

TEST(CubeBakerTest, RotatedBoxCoversTheRightSamples) {
    constexpr int kResolution = 8;
    CubeBaker baker(kResolution);
    baker.reset(glm::vec3(0.0f), glm::vec3(1.0f));
    const ColorCube box = distinctOpaqueCube();
    // The box [-0.25, 0.25]^3 turned 45 degrees about Z and centred in the cell: a diamond
    // |x - 0.5| + |y - 0.5| <= 0.25 * sqrt(2) seen along Z.
    const glm::mat4 transform = glm::rotate(
            glm::translate(glm::mat4(1.0f), glm::vec3(0.5f)),
            glm::radians(45.0f),
            glm::vec3(0.0f, 0.0f, 1.0f));
    baker.addBox(transform, glm::vec3(-0.25f), glm::vec3(0.25f), box);
    const ColorCube cube = baker.finish();

    int diamond = 0;
    for (int j = 0; j < kResolution; ++j) {
        for (int i = 0; i < kResolution; ++i) {
            const float x = (static_cast<float>(i) + 0.5f) / kResolution - 0.5f;
            const float y = (static_cast<float>(j) + 0.5f) / kResolution - 0.5f;
            diamond += std::fabs(x) + std::fabs(y) <= 0.25f * std::sqrt(2.0f) ? 1 : 0;
        }
    }
    ASSERT_EQ(diamond, 12); // distances 0.125 (4 samples) and 0.25 (8); the next is 0.375
    const float zCoverage = static_cast<float>(diamond) / (kResolution * kResolution);
    expectFaceNear(cube, kFacePlusZ, zCoverage * box.faces[kFacePlusZ]);
    expectFaceNear(cube, kFaceMinusZ, zCoverage * box.faces[kFaceMinusZ]);

    // Seen along +X the box spans y in 0.5 +- 0.354 (samples 1..6) and z in [0.25, 0.75]
    // (samples 2..5): 24 samples. The local +X face (turned towards +X+Y) fills the upper half in
    // y, the local -Y face (turned towards +X-Y) the lower half.
    const glm::vec4 expectedPlusX =
            (12.0f * box.faces[kFacePlusX] + 12.0f * box.faces[kFaceMinusY]) / 64.0f;
    expectFaceNear(cube, kFacePlusX, expectedPlusX);
    // Seen along +Y: local +X (upper half in x) and local +Y (lower half in x).
    const glm::vec4 expectedPlusY =
            (12.0f * box.faces[kFacePlusX] + 12.0f * box.faces[kFacePlusY]) / 64.0f;
    expectFaceNear(cube, kFacePlusY, expectedPlusY);
}

TEST(CubeBakerTest, BoxSmallerThanASampleStillContributesItsArea) {
    CubeBaker baker(4);
    baker.reset(glm::vec3(0.0f), glm::vec3(1.0f));
    // 0.05 x 0.05 between sample centres: 0.04 of a sample (sample = 0.25 x 0.25).
    baker.addBox(
            glm::mat4(1.0f),
            glm::vec3(0.3f, 0.3f, 0.3f),
            glm::vec3(0.35f, 0.35f, 0.35f),
            uniformCube(glm::vec4(1.0f)));
    const ColorCube cube = baker.finish();
    for (int face = 0; face < storage::kCubeFaceCount; ++face)
        EXPECT_NEAR(cube.faces[static_cast<std::size_t>(face)].a, 0.04f / 16.0f, 1e-5f)
                << "face " << face;
}

// ---- finish() with an underlay ---------------------------------------------------------------

class CubeBakerUnderlayTest : public ::testing::TestWithParam<int> {};

TEST_P(CubeBakerUnderlayTest, UnderlayAloneEqualsCompositeOctants) {
    std::array<ColorCube, 8> cubes;
    std::array<const ColorCube*, 8> children{};
    for (std::size_t o = 0; o < 8; ++o) {
        if (o == 2 || o == 7)
            continue; // some children missing
        const float a = 0.125f * static_cast<float>(o + 1);
        for (int f = 0; f < storage::kCubeFaceCount; ++f)
            cubes[o].faces[static_cast<std::size_t>(f)] =
                    glm::vec4(0.5f * a, 0.25f * a, 0.0625f * static_cast<float>(f) * a, a);
        children[o] = &cubes[o];
    }
    const QuadrantColors underlay = compositeOctantQuadrants(children);
    const ColorCube expected = compositeOctants(children);

    CubeBaker baker(GetParam());
    baker.reset(glm::vec3(0.0f), glm::vec3(2.0f));
    const ColorCube cube = baker.finish(&underlay);
    for (int face = 0; face < storage::kCubeFaceCount; ++face)
        expectFaceNear(cube, face, expected.faces[static_cast<std::size_t>(face)]);
}

// Odd resolutions put a row and a column of samples on the quadrant boundaries.
INSTANTIATE_TEST_SUITE_P(Resolutions, CubeBakerUnderlayTest, ::testing::Values(2, 3, 5, 8, 9));

TEST(CubeBakerTest, TrianglesCoverTheUnderlay) {
    std::array<ColorCube, 8> cubes;
    std::array<const ColorCube*, 8> children{};
    for (std::size_t o = 0; o < 8; ++o) {
        cubes[o] = uniformCube(glm::vec4(0.0f, 0.0f, 0.5f, 0.5f));
        children[o] = &cubes[o];
    }
    const QuadrantColors underlay = compositeOctantQuadrants(children);
    CubeBaker baker(8);
    baker.reset(glm::vec3(0.0f), glm::vec3(1.0f));
    const std::vector<storage::PackedTriangle> quad =
            quadZ(0.0f, 0.5f, 0.0f, 1.0f, 0.5f, {1.0f, 1.0f, 0.0f});
    baker.addTriangles(quad);
    const ColorCube cube = baker.finish(&underlay);
    // Half the samples see the opaque quad, the other half the children (two 0.5-alpha layers).
    const glm::vec4 children2 =
            over(glm::vec4(0.0f, 0.0f, 0.5f, 0.5f), glm::vec4(0.0f, 0.0f, 0.5f, 0.5f));
    const glm::vec4 expected =
            0.5f * glm::vec4(shadedColor(quad[0].vertices[0]), 1.0f) + 0.5f * children2;
    expectFaceNear(cube, kFacePlusZ, expected);
    // The X viewers see the quad edge-on: only the children.
    expectFaceNear(cube, kFacePlusX, children2);
}

} // namespace
} // namespace ff::builder
