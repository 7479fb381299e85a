// `farfield render` end to end: glTF cameras carried through the scene file, and clear errors.

#include "FarfieldProcess.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <string>
#include <vector>

namespace ff::viewer::test {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

bool exitedWith(const ProcessResult& r, int code) {
    return r.exited && r.exitCode == code;
}

std::string base64(const std::vector<unsigned char>& bytes) {
    static constexpr char kAlphabet[] =
            "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    std::size_t i = 0;
    for (; i + 2 < bytes.size(); i += 3) {
        const std::uint32_t v =
                (std::uint32_t{bytes[i]} << 16) | (std::uint32_t{bytes[i + 1]} << 8) | bytes[i + 2];
        for (int shift = 18; shift >= 0; shift -= 6)
            out += kAlphabet[(v >> shift) & 63];
    }
    if (i < bytes.size()) {
        std::uint32_t v = std::uint32_t{bytes[i]} << 16;
        if (i + 1 < bytes.size())
            v |= std::uint32_t{bytes[i + 1]} << 8;
        out += kAlphabet[(v >> 18) & 63];
        out += kAlphabet[(v >> 12) & 63];
        out += i + 1 < bytes.size() ? kAlphabet[(v >> 6) & 63] : '=';
        out += '=';
    }
    return out;
}

void appendFloats(std::vector<unsigned char>& out, std::initializer_list<float> values) {
    for (float v : values) {
        unsigned char raw[sizeof(float)];
        std::memcpy(raw, &v, sizeof(float));
        out.insert(out.end(), raw, raw + sizeof(float));
    }
}

/**
 * A .gltf with its buffer in a data: URI: two unit quads (4 triangles, no indices), one in the
 * z = 0 plane at the origin and one 3 units to the right, plus a perspective camera that
 * hovers in front of the second quad only. The orbit view frames both.
 */
json cameraGltf() {
    std::vector<unsigned char> buffer;
    appendFloats(buffer, {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 0, 0, 1, 1, 0, 0, 1, 0});
    return json{
            {"asset", {{"version", "2.0"}}},
            {"scene", 0},
            {"scenes", {{{"nodes", {0, 1, 2}}}}},
            {"nodes",
             {{{"mesh", 0}},
              {{"mesh", 0}, {"translation", {3, 0, 0}}},
              {{"camera", 0}, {"translation", {3.5, 0.5, 1.2}}}}},
            {"cameras",
             {{{"type", "perspective"},
               {"perspective",
                {{"yfov", 0.8}, {"znear", 0.05}, {"zfar", 100.0}, {"aspectRatio", 4.0 / 3.0}}}}}},
            {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}}}, {"material", 0}}}}}}},
            {"materials",
             {{{"pbrMetallicRoughness", {{"baseColorFactor", {0.9, 0.3, 0.1, 1.0}}}},
               {"doubleSided", true}}}},
            {"accessors",
             {{{"bufferView", 0},
               {"componentType", 5126},
               {"count", 6},
               {"type", "VEC3"},
               {"min", {0, 0, 0}},
               {"max", {1, 1, 0}}}}},
            {"bufferViews", {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", buffer.size()}}}},
            {"buffers",
             {{{"byteLength", buffer.size()},
               {"uri", "data:application/octet-stream;base64," + base64(buffer)}}}}};
}

TEST(RenderCommandTest, GltfCameraRendersItsOwnView) {
    const fs::path dir = freshTestDir();
    const fs::path gltf = dir / "camera.gltf";
    std::ofstream(gltf) << cameraGltf().dump(1);
    const fs::path scene = dir / "camera.ffs";
    const ProcessResult built =
            runFarfield({"build", "-q", gltf.string(), "-o", scene.string()}, dir);
    ASSERT_TRUE(exitedWith(built, 0)) << built.describe();

    const auto render = [&](const std::string& name, std::vector<std::string> flags) {
        const fs::path png = dir / (name + ".png");
        std::vector<std::string> args = {
                "render",
                scene.string(),
                "-o",
                png.string(),
                "--size",
                "160x120",
                "--coverage-alpha"};
        args.insert(args.end(), flags.begin(), flags.end());
        const ProcessResult r = runFarfield(args, dir);
        EXPECT_TRUE(exitedWith(r, 0)) << r.describe();
        return decodeImage(png);
    };
    const runtime::Image orbit = render("orbit", {});
    const runtime::Image camera = render("camera", {"--camera", "gltf:0"});
    const std::uint64_t pixels = 160u * 120u;
    ASSERT_EQ(orbit.rgba.size(), pixels * 4);
    ASSERT_EQ(camera.rgba.size(), pixels * 4);
    EXPECT_GT(coveredPixels(orbit), 0u);
    // The camera sits 1.2 units in front of the right quad's centre with a 46 degree field of
    // view: that quad fills most of the frame, the other is out of view.
    EXPECT_GT(coveredPixels(camera), pixels / 3);
    EXPECT_GT(coveredPixels(camera), 2 * coveredPixels(orbit));
    EXPECT_GT(differingPixels(orbit, camera), pixels / 4);
    // The centre of the camera's view is the quad itself.
    EXPECT_EQ(camera.pixel(80, 60)[3], 255);
}

TEST(RenderCommandTest, CameraIndexBeyondTheSceneIsAClearError) {
    const fs::path dir = freshTestDir();
    const fs::path scene = dir / "tree.ffs";
    const ProcessResult built =
            runFarfield({"build", "-q", "--generate", "forest:trees=1", "-o", scene.string()}, dir);
    ASSERT_TRUE(exitedWith(built, 0)) << built.describe();
    const ProcessResult r =
            runFarfield({"render", scene.string(), "--camera", "gltf:5", "--size", "32x24"}, dir);
    EXPECT_TRUE(exitedWith(r, 1)) << r.describe();
    EXPECT_NE(r.err.find("gltf:5"), std::string::npos) << r.describe();
    EXPECT_NE(r.err.find("0 glTF camera"), std::string::npos) << r.describe();
    const ProcessResult malformed =
            runFarfield({"render", scene.string(), "--camera", "orbit:1"}, dir);
    EXPECT_TRUE(exitedWith(malformed, 2)) << malformed.describe();
}

TEST(RenderCommandTest, MissingSceneFileIsAClearError) {
    const fs::path dir = freshTestDir();
    const fs::path missing = dir / "missing.ffs";
    const ProcessResult r =
            runFarfield({"render", missing.string(), "-o", (dir / "x.png").string()}, dir);
    EXPECT_TRUE(exitedWith(r, 1)) << r.describe();
    EXPECT_EQ(r.err.rfind("farfield render: ", 0), 0u) << r.describe();
    EXPECT_NE(r.err.find(missing.string()), std::string::npos) << r.describe();
    EXPECT_FALSE(fs::exists(dir / "x.png"));
    const ProcessResult checked = runFarfield({"check", missing.string()}, dir);
    EXPECT_TRUE(exitedWith(checked, 1)) << checked.describe();
    // A file that is not a scene at all.
    std::ofstream(dir / "text.ffs") << "hello, not a scene\n";
    const ProcessResult text = runFarfield({"render", (dir / "text.ffs").string()}, dir);
    EXPECT_TRUE(exitedWith(text, 1)) << text.describe();
    EXPECT_NE(text.err.find("page 0"), std::string::npos) << text.describe();
}

} // namespace
} // namespace ff::viewer::test
