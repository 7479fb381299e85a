// Scenes of slabs written as glTF (one unit box mesh, each node's matrix making a slab of it, in
// front of a backdrop box), rendered end to end.
//
// Color cubes under instance transforms that are not a uniform scale: every cube drawing mode
// against the supersampled reference. 200 slabs make a venetian blind built from instances. The
// point-drawn cubes once took the transform's x-axis scale as the scale of every length: the
// blind's slabs (10, 0.004, 1) turned into points 10^4 times too large (13.3 dB against 33.4 dB
// for faces, issue 13).
//
// Unlit materials (KHR_materials_unlit): the base colour as it is, as triangles and as cubes.

#include "FarfieldProcess.h"

#include <ff/runtime/ImageMetrics.h>
#include <ff/storage/VertexCodec.h>

#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

namespace ff::viewer::test {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

json matrixOf(const glm::mat4& m) {
    const float* values = glm::value_ptr(m); // column-major, as glTF's "matrix"
    return json(std::vector<float>(values, values + 16));
}

constexpr int kBoxTessellation = 12; ///< quads per face edge: the prototype gets an octree of cells

/** The unit box [-0.5, 0.5]³, each face split into kBoxTessellation² quads, as float positions
 *  then uint16 indices (outward winding, no normals: the builder gives each triangle its face
 *  normal). Tessellated so that the prototype has inner cells, which are drawn as cubes under
 *  the instance's own transform. */
std::vector<unsigned char> unitBoxBuffer(std::size_t& vertexCount, std::size_t& indexCount) {
    std::vector<float> positions;
    std::vector<std::uint16_t> indices;
    const int n = kBoxTessellation;
    for (int axis = 0; axis < 3; ++axis) {
        for (int side = 0; side < 2; ++side) {
            const auto base = static_cast<std::uint16_t>(positions.size() / 3);
            for (int j = 0; j <= n; ++j) {
                for (int i = 0; i <= n; ++i) {
                    float p[3];
                    p[axis] = side ? 0.5f : -0.5f;
                    p[(axis + 1) % 3] = static_cast<float>(i) / static_cast<float>(n) - 0.5f;
                    p[(axis + 2) % 3] = static_cast<float>(j) / static_cast<float>(n) - 0.5f;
                    positions.insert(positions.end(), p, p + 3);
                }
            }
            for (int j = 0; j < n; ++j) {
                for (int i = 0; i < n; ++i) {
                    const auto at = [&](int di, int dj) {
                        return static_cast<std::uint16_t>(base + (j + dj) * (n + 1) + i + di);
                    };
                    // (u, v) = (axis + 1, axis + 2) is right-handed with the axis:
                    // counter-clockwise seen from outside on the + side, so the - side flips the
                    // winding.
                    if (side)
                        indices.insert(
                                indices.end(),
                                {at(0, 0), at(1, 0), at(1, 1), at(0, 0), at(1, 1), at(0, 1)});
                    else
                        indices.insert(
                                indices.end(),
                                {at(0, 0), at(1, 1), at(1, 0), at(0, 0), at(0, 1), at(1, 1)});
                }
            }
        }
    }
    vertexCount = positions.size() / 3;
    indexCount = indices.size();
    std::vector<unsigned char> bytes(positions.size() * 4 + indices.size() * 2);
    std::memcpy(bytes.data(), positions.data(), positions.size() * 4);
    std::memcpy(bytes.data() + positions.size() * 4, indices.data(), indices.size() * 2);
    return bytes;
}

const json kRedLit = {{"pbrMetallicRoughness", {{"baseColorFactor", {0.8, 0.1, 0.1, 1.0}}}}};

/**
 * Writes dir/name.gltf (+ .bin): one slab node of `slabMaterial` per entry of `slabs` (children
 * of a parent node with `parent` as its matrix) and, if `withBackdrop`, a grey backdrop box,
 * 12 x 12 x 0.5, at z = -3.
 */
fs::path writeSlabScene(
        const fs::path& dir,
        const std::string& name,
        const glm::mat4& parent,
        const std::vector<glm::mat4>& slabs,
        const json& slabMaterial = kRedLit,
        bool withBackdrop = true) {
    std::size_t vertexCount = 0;
    std::size_t indexCount = 0;
    const std::vector<unsigned char> buffer = unitBoxBuffer(vertexCount, indexCount);
    writeBytes(dir / (name + ".bin"), buffer);
    json nodes = json::array();
    json children = json::array();
    for (std::size_t i = 0; i < slabs.size(); ++i) {
        nodes.push_back({{"mesh", 0}, {"matrix", matrixOf(slabs[i])}});
        children.push_back(i);
    }
    const glm::mat4 backdrop =
            glm::scale(glm::translate(glm::mat4(1.0f), {0.0f, 0.0f, -3.0f}), {12.0f, 12.0f, 0.5f});
    nodes.push_back({{"mesh", 1}, {"matrix", matrixOf(backdrop)}});
    nodes.push_back({{"children", children}, {"matrix", matrixOf(parent)}});
    const json roots = withBackdrop ? json{slabs.size(), slabs.size() + 1} : json{slabs.size() + 1};
    auto primitive = [](int material) {
        return json{{"attributes", {{"POSITION", 0}}}, {"indices", 1}, {"material", material}};
    };
    const json gltf = {
            {"asset", {{"version", "2.0"}}},
            {"scene", 0},
            {"scenes", {{{"nodes", roots}}}},
            {"nodes", nodes},
            {"materials",
             {slabMaterial,
              {{"pbrMetallicRoughness", {{"baseColorFactor", {0.5, 0.5, 0.5, 1.0}}}}}}},
            {"meshes", {{{"primitives", {primitive(0)}}}, {{"primitives", {primitive(1)}}}}},
            {"accessors",
             {{{"bufferView", 0},
               {"componentType", 5126},
               {"count", vertexCount},
               {"type", "VEC3"},
               {"min", {-0.5, -0.5, -0.5}},
               {"max", {0.5, 0.5, 0.5}}},
              {{"bufferView", 1},
               {"componentType", 5123},
               {"count", indexCount},
               {"type", "SCALAR"}}}},
            {"bufferViews",
             {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", vertexCount * 12}},
              {{"buffer", 0}, {"byteOffset", vertexCount * 12}, {"byteLength", indexCount * 2}}}},
            {"buffers", {{{"byteLength", buffer.size()}, {"uri", name + ".bin"}}}}};
    const fs::path path = dir / (name + ".gltf");
    std::ofstream(path) << gltf.dump(1);
    return path;
}

/** `count` slabs: `shape` (the slab's own matrix) placed `spacing` apart along `stackAxis`,
 *  centred on the origin. */
std::vector<glm::mat4>
stack(int count, float spacing, const glm::vec3& stackAxis, const glm::mat4& shape) {
    std::vector<glm::mat4> slabs;
    for (int i = 0; i < count; ++i) {
        const float offset =
                (static_cast<float>(i) - 0.5f * static_cast<float>(count - 1)) * spacing;
        slabs.push_back(glm::translate(glm::mat4(1.0f), offset * stackAxis) * shape);
    }
    return slabs;
}

glm::mat4 scaling(float x, float y, float z) {
    return glm::scale(glm::mat4(1.0f), {x, y, z});
}

struct TransformCase {
    const char* name;
    glm::mat4 parent;
    std::vector<glm::mat4> slabs;
    double minimumDefaultPsnr; ///< at the near view: an absolute floor where the issue set one,
                               ///< else 0
};

std::vector<TransformCase> transformCases() {
    const glm::vec3 x(1, 0, 0), y(0, 1, 0), z(0, 0, 1);
    glm::mat4 shear = scaling(10.0f, 0.004f, 1.0f);
    shear[2] = glm::vec4(0.6f, 0.0f, 1.0f, 0.0f); // the slab's z axis leans towards +x
    const glm::mat4 turned = glm::rotate(
            glm::mat4(1.0f), glm::radians(35.0f), glm::normalize(glm::vec3(1, 2, 0.5f)));
    return {
            // The blind of issue 13 (there 13.3 dB against 33.4 with faces). Here, with the
            // tessellated box: 34.4 dB for every mode, 17.0 for points with the former ε rule.
            {"blind, y thin",
             glm::mat4(1.0f),
             stack(200, 0.05f, y, scaling(10.0f, 0.004f, 1.0f)),
             32.4},
            {"blind, x thin",
             glm::mat4(1.0f),
             stack(200, 0.05f, x, scaling(0.004f, 10.0f, 1.0f)),
             0.0},
            {"blind, z thin",
             glm::mat4(1.0f),
             stack(200, 0.05f, z, scaling(10.0f, 1.0f, 0.004f)),
             0.0},
            {"mirrored",
             glm::mat4(1.0f),
             stack(200, 0.05f, y, scaling(-10.0f, 0.004f, 1.0f)), // det < 0: a mirror
             0.0},
            {"sheared", glm::mat4(1.0f), stack(200, 0.05f, y, shear), 0.0},
            // A rotated, non-uniformly scaled parent over non-uniformly scaled children.
            {"nested scales",
             turned * scaling(5.0f, 1.0f, 0.5f),
             stack(200, 0.05f, y, scaling(2.0f, 0.004f, 2.0f)),
             0.0},
    };
}

double psnr(const runtime::Image& approximation, const runtime::Image& reference) {
    const Result<runtime::ColorError> error = runtime::colorError(approximation, reference);
    EXPECT_TRUE(error.isOk()) << error.status().toString();
    return error.isOk() ? error->psnrSrgb : 0.0;
}

// On every case the default cube drawing (points at ε = 1) and points stay within 1 dB of
// drawing the cubes' faces, both measured against the 4x4 supersampled full render.
TEST(CubeDrawTransformTest, PointsMatchFacesUnderNonUniformMirroredShearedAndNestedScales) {
    const fs::path dir = freshTestDir();
    for (const TransformCase& c : transformCases()) {
        SCOPED_TRACE(c.name);
        const fs::path gltf = writeSlabScene(dir, "slabs", c.parent, c.slabs);
        const fs::path scene = dir / "slabs.ffs";
        const ProcessResult built =
                runFarfield({"build", "-q", gltf.string(), "-o", scene.string()}, dir);
        ASSERT_EQ(built.exitCode, 0) << built.describe();
        // Near (the view of issue 13: every slab is refined to its triangles once the ε rule
        // measures it in world units) and far (100 radii: slabs are sub-pixel cubes, drawn as
        // points whose size must come from the whole transform).
        for (const char* distance : {"2.5", "100"}) {
            SCOPED_TRACE(std::string("distance ") + distance);
            const std::vector<std::string> view = {
                    "--size",
                    "320x240",
                    "--distance",
                    distance,
                    "--azimuth",
                    "30",
                    "--elevation",
                    "20"};
            auto render = [&](const std::string& name, std::vector<std::string> flags) {
                std::vector<std::string> args = {
                        "render", scene.string(), "-o", (dir / name).string()};
                args.insert(args.end(), view.begin(), view.end());
                args.insert(args.end(), flags.begin(), flags.end());
                const ProcessResult r = runFarfield(args, dir);
                EXPECT_EQ(r.exitCode, 0) << r.describe();
                return decodeImage(dir / name);
            };
            const runtime::Image reference =
                    render("reference.png", {"--method", "full", "--supersample", "4"});
            ASSERT_EQ(reference.width, 320);
            const double faces = psnr(render("faces.png", {"--cube-draw", "faces"}), reference);
            const double points = psnr(render("points.png", {"--cube-draw", "points"}), reference);
            const double automatic = psnr(render("auto.png", {}), reference);
            std::printf(
                    "%-14s at %5s radii: faces %.2f dB, points %.2f dB, auto %.2f dB\n",
                    c.name,
                    distance,
                    faces,
                    points,
                    automatic);
            EXPECT_GE(points, faces - 1.0);
            EXPECT_GE(automatic, faces - 1.0);
            if (std::string(distance) == "2.5") {
                EXPECT_GE(automatic, c.minimumDefaultPsnr);
            }
        }
    }
}

fs::path buildSlabScene(const fs::path& dir, const fs::path& gltf) {
    const fs::path scene = dir / (gltf.stem().string() + ".ffs");
    const ProcessResult built =
            runFarfield({"build", "-q", gltf.string(), "-o", scene.string()}, dir);
    EXPECT_EQ(built.exitCode, 0) << built.describe();
    return scene;
}

/** The centre pixel of `scene` rendered 160x120 straight down -z from 3 units, with `flags`. */
std::array<std::uint8_t, 4>
centrePixel(const fs::path& dir, const fs::path& scene, std::vector<std::string> flags) {
    std::vector<std::string> args = {
            "render",
            scene.string(),
            "-o",
            (dir / "centre.png").string(),
            "--size",
            "160x120",
            "--eye",
            "0,0,3",
            "--target",
            "0,0,0"};
    args.insert(args.end(), flags.begin(), flags.end());
    const ProcessResult r = runFarfield(args, dir);
    EXPECT_EQ(r.exitCode, 0) << r.describe();
    const runtime::Image image = decodeImage(dir / "centre.png");
    if (image.width != 160 || image.height != 120)
        return {};
    const std::uint8_t* p = image.pixel(80, 60);
    return {p[0], p[1], p[2], p[3]};
}

// One slab 4 x 4 x 0.1 facing the camera, alone: unlit, its front face shows the base colour's
// sRGB codes exactly as triangles (the lit twin is darker: the light is 66 degrees off its
// normal), and within two codes as the root's colour cube drawn as faces (ε large enough for
// the root).
TEST(UnlitMaterialTest, UnlitSurfacesShowTheirBaseColourAsTrianglesAndAsCubes) {
    const fs::path dir = freshTestDir();
    const std::vector<glm::mat4> slab = {scaling(4.0f, 4.0f, 0.1f)};
    json unlitMaterial = kRedLit;
    unlitMaterial["extensions"] = {{"KHR_materials_unlit", json::object()}};
    const fs::path lit =
            buildSlabScene(dir, writeSlabScene(dir, "lit", glm::mat4(1.0f), slab, kRedLit, false));
    const fs::path unlit = buildSlabScene(
            dir, writeSlabScene(dir, "unlit", glm::mat4(1.0f), slab, unlitMaterial, false));
    const std::array<std::uint8_t, 3> base = {
            storage::linearToSrgb8(0.8f),
            storage::linearToSrgb8(0.1f),
            storage::linearToSrgb8(0.1f)};

    const auto triangles = centrePixel(dir, unlit, {"--epsilon", "0"});
    EXPECT_EQ(triangles[0], base[0]);
    EXPECT_EQ(triangles[1], base[1]);
    EXPECT_EQ(triangles[2], base[2]);
    const auto litTriangles = centrePixel(dir, lit, {"--epsilon", "0"});
    EXPECT_LT(litTriangles[0] + 10, base[0]);

    const auto cube = centrePixel(dir, unlit, {"--epsilon", "1000", "--cube-draw", "faces"});
    for (std::size_t c = 0; c < 3; ++c)
        EXPECT_NEAR(cube[c], base[c], 2) << "channel " << c;
    const auto litCube = centrePixel(dir, lit, {"--epsilon", "1000", "--cube-draw", "faces"});
    EXPECT_LT(litCube[0] + 10, base[0]);
}

} // namespace
} // namespace ff::viewer::test
