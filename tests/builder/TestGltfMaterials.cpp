// Material inputs the importer keeps: KHR_texture_transform on the base colour texture (checked
// against texels computed here by hand) and KHR_materials_unlit (stored as the unlit normal
// code). The models are written here: a quad with two UV sets and a 4 x 4 PNG.

#include "GltfMaterial.h"
#include "RecordingSink.h"

#include <ff/builder/GltfImporter.h>
#include <ff/storage/VertexCodec.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <stb_image_write.h>

#include <array>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

namespace ff::builder {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
using testing::RecordingSink;

constexpr int kSide = 4;

/** sRGB codes of texel (x, y) of the test texture: every texel differs. */
std::array<std::uint8_t, 4> texel(int x, int y) {
    return {static_cast<std::uint8_t>(40 + 60 * x),
            static_cast<std::uint8_t>(40 + 60 * y),
            128,
            255};
}

fs::path freshDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    const fs::path dir =
            fs::path(FF_TEST_TMP_DIR) / (std::string(info->test_suite_name()) + "." + info->name());
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir;
}

void writeTexture(const fs::path& path) {
    std::vector<std::uint8_t> rgba;
    for (int y = 0; y < kSide; ++y)
        for (int x = 0; x < kSide; ++x)
            for (std::uint8_t c : texel(x, y))
                rgba.push_back(c);
    ASSERT_NE(stbi_write_png(path.c_str(), kSide, kSide, 4, rgba.data(), kSide * 4), 0);
}

/**
 * dir/quad.gltf: two triangles over 4 vertices, TEXCOORD_0 all (0.9, 0.9) (a set the transform's
 * texCoord override must not read) and TEXCOORD_1 = `uv1`, textured with dir/texture.png through
 * `textureInfo`, and with `materialExtensions` on the material.
 */
fs::path writeQuad(
        const fs::path& dir,
        const std::array<float, 8>& uv1,
        const json& textureInfo,
        const json& materialExtensions = json::object(),
        const json& required = json::array()) {
    writeTexture(dir / "texture.png");
    const std::vector<float> positions = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};
    const std::vector<float> uv0(8, 0.9f);
    const std::vector<std::uint16_t> indices = {0, 1, 2, 2, 1, 3};
    std::vector<unsigned char> bin(48 + 32 + 32 + 12);
    std::memcpy(bin.data(), positions.data(), 48);
    std::memcpy(bin.data() + 48, uv0.data(), 32);
    std::memcpy(bin.data() + 80, uv1.data(), 32);
    std::memcpy(bin.data() + 112, indices.data(), 12);
    std::ofstream(dir / "quad.bin", std::ios::binary)
            .write(reinterpret_cast<const char*>(bin.data()),
                   static_cast<std::streamsize>(bin.size()));
    json material = {{"pbrMetallicRoughness", {{"baseColorTexture", textureInfo}}}};
    if (!materialExtensions.empty())
        material["extensions"] = materialExtensions;
    json gltf = {
            {"asset", {{"version", "2.0"}}},
            {"scene", 0},
            {"scenes", {{{"nodes", {0}}}}},
            {"nodes", {{{"mesh", 0}}}},
            {"meshes",
             {{{"primitives",
                {{{"attributes", {{"POSITION", 0}, {"TEXCOORD_0", 1}, {"TEXCOORD_1", 2}}},
                  {"indices", 3},
                  {"material", 0}}}}}}},
            {"materials", {material}},
            {"textures", {{{"source", 0}}}},
            {"images", {{{"uri", "texture.png"}}}},
            {"accessors",
             {{{"bufferView", 0},
               {"componentType", 5126},
               {"count", 4},
               {"type", "VEC3"},
               {"min", {0, 0, 0}},
               {"max", {1, 1, 0}}},
              {{"bufferView", 1}, {"componentType", 5126}, {"count", 4}, {"type", "VEC2"}},
              {{"bufferView", 2}, {"componentType", 5126}, {"count", 4}, {"type", "VEC2"}},
              {{"bufferView", 3}, {"componentType", 5123}, {"count", 6}, {"type", "SCALAR"}}}},
            {"bufferViews",
             {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 48}},
              {{"buffer", 0}, {"byteOffset", 48}, {"byteLength", 32}},
              {{"buffer", 0}, {"byteOffset", 80}, {"byteLength", 32}},
              {{"buffer", 0}, {"byteOffset", 112}, {"byteLength", 12}}}},
            {"buffers", {{{"byteLength", bin.size()}, {"uri", "quad.bin"}}}}};
    if (!required.empty()) {
        gltf["extensionsUsed"] = required;
        gltf["extensionsRequired"] = required;
    }
    const fs::path path = dir / "quad.gltf";
    std::ofstream(path) << gltf.dump(1);
    return path;
}

struct Imported {
    RecordingSink sink;
    Result<GltfImportReport> result = Status{ErrorCode::Internal, "not run"};
};

std::unique_ptr<Imported> importFile(const fs::path& path) {
    auto out = std::make_unique<Imported>();
    out->result = importGltf(path, out->sink, {});
    return out;
}

/** Vertex `index` of the quad (0..3) as imported: triangles {0,1,2} and {2,1,3}. */
const storage::PackedVertex& quadVertex(const Imported& imported, int index) {
    const auto& triangles = imported.sink.prototypes().at(0).triangles;
    static constexpr std::array<std::pair<int, int>, 4> kWhere = {{{0, 0}, {0, 1}, {0, 2}, {1, 2}}};
    const auto [triangle, corner] = kWhere[static_cast<std::size_t>(index)];
    return triangles.at(static_cast<std::size_t>(triangle))
            .vertices[static_cast<std::size_t>(corner)];
}

// offset (0.25, 0), rotation π/2, scale (0.5, 0.5), texCoord 1. By hand, uv' = T R S uv with
// R = [[cos, sin], [-sin, cos]] (as cesium-native and three.js apply the extension):
// S uv = (a/2, b/2); R: (b/2, -a/2); T: (b/2 + 1/4, -a/2). With the texture repeating, each
// vertex lands on a texel centre ((i + 1/2) / 4):
//   (0.25, 0.25) -> (0.375, -0.125 = 0.875) -> texel (1, 3)
//   (0.75, 0.25) -> (0.375, -0.375 = 0.625) -> texel (1, 2)
//   (0.25, 1.25) -> (0.875, -0.125 = 0.875) -> texel (3, 3)
//   (1.25, 0.75) -> (0.625, -0.625 = 0.375) -> texel (2, 1)
// Without the transform (or with the rotation the other way) other texels come out.
TEST(GltfMaterialTest, TextureTransformMovesTheBaseColourLookupToHandComputedTexels) {
    const fs::path dir = freshDir();
    const json transform = {
            {"offset", {0.25, 0.0}},
            {"rotation", std::numbers::pi / 2},
            {"scale", {0.5, 0.5}},
            {"texCoord", 1}};
    const fs::path path = writeQuad(
            dir,
            {0.25f, 0.25f, 0.75f, 0.25f, 0.25f, 1.25f, 1.25f, 0.75f},
            {{"index", 0}, {"extensions", {{"KHR_texture_transform", transform}}}},
            json::object(),
            {"KHR_texture_transform"});
    const auto imported = importFile(path);
    ASSERT_TRUE(imported->result.isOk()) << imported->result.status().toString();
    const std::array<std::array<int, 2>, 4> expected = {{{1, 3}, {1, 2}, {3, 3}, {2, 1}}};
    for (int v = 0; v < 4; ++v) {
        SCOPED_TRACE("vertex " + std::to_string(v));
        const auto want = texel(
                expected[static_cast<std::size_t>(v)][0], expected[static_cast<std::size_t>(v)][1]);
        const auto& got = quadVertex(*imported, v).color;
        for (std::size_t c = 0; c < 4; ++c)
            EXPECT_NEAR(got[c], want[c], 1) << "channel " << c;
    }
    EXPECT_TRUE(imported->result->warnings.empty()) << imported->result->warnings.front();
}

TEST(GltfMaterialTest, TextureTransformWithBadValuesIsRefusedWithItsName) {
    const fs::path dir = freshDir();
    for (const json& transform :
         {json{{"scale", {1.0}}},
          json{{"rotation", "a lot"}},
          json{{"offset", {0, "x"}}},
          json{{"texCoord", -1}}}) {
        SCOPED_TRACE(transform.dump());
        const fs::path path = writeQuad(
                dir, {}, {{"index", 0}, {"extensions", {{"KHR_texture_transform", transform}}}});
        const auto imported = importFile(path);
        ASSERT_FALSE(imported->result.isOk());
        EXPECT_EQ(imported->result.status().code(), ErrorCode::InvalidInput);
        EXPECT_NE(
                imported->result.status().message().find("KHR_texture_transform"),
                std::string::npos)
                << imported->result.status().toString();
    }
}

TEST(GltfMaterialTest, UvTransformIsTranslationRotationScaleInThatOrder) {
    UvTransform t;
    EXPECT_TRUE(t.isIdentity());
    EXPECT_EQ(t.apply({0.3f, 0.7f}), glm::vec2(0.3f, 0.7f));
    t.offset = {1.0, 2.0};
    t.scale = {2.0, 3.0};
    t.rotation = std::numbers::pi; // (u, v) -> (-u, -v)
    const glm::vec2 out = t.apply({1.0f, 1.0f});
    EXPECT_NEAR(out.x, 1.0f - 2.0f, 1e-6f);
    EXPECT_NEAR(out.y, 2.0f - 3.0f, 1e-6f);
}

// KHR_materials_unlit, required: imported, and every vertex carries the unlit code (the renderer
// and the cube baker then skip the light); the same model without the extension is lit.
TEST(GltfMaterialTest, UnlitMaterialsGiveUnlitVertices) {
    const fs::path dir = freshDir();
    const std::array<float, 8> uv = {
            0.125f, 0.125f, 0.375f, 0.125f, 0.125f, 0.375f, 0.375f, 0.375f};
    const auto unlit = importFile(writeQuad(
            dir,
            uv,
            {{"index", 0}},
            {{"KHR_materials_unlit", json::object()}},
            {"KHR_materials_unlit"}));
    ASSERT_TRUE(unlit->result.isOk()) << unlit->result.status().toString();
    for (int v = 0; v < 4; ++v)
        EXPECT_TRUE(storage::isUnlitNormal(quadVertex(*unlit, v).normalOct)) << "vertex " << v;
    const auto lit = importFile(writeQuad(dir, uv, {{"index", 0}}));
    ASSERT_TRUE(lit->result.isOk()) << lit->result.status().toString();
    for (int v = 0; v < 4; ++v)
        EXPECT_FALSE(storage::isUnlitNormal(quadVertex(*lit, v).normalOct)) << "vertex " << v;
}

} // namespace
} // namespace ff::builder
