#include "RecordingSink.h"
#include "TextureSampler.h"

#include <ff/builder/GltfImporter.h>
#include <ff/storage/VertexCodec.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace ff::builder {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
using testing::RecordingSink;

const fs::path kData = FF_SHARED_DATA_DIR;

fs::path tempDir() {
    const fs::path dir = fs::path(FF_TEST_TMP_DIR) / "gltf";
    fs::create_directories(dir);
    return dir;
}

std::vector<unsigned char> readBytes(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void writeBytes(const fs::path& path, const std::vector<unsigned char>& bytes) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(
            reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
}

void writeText(const fs::path& path, const std::string& text) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out << text;
}

std::uint32_t u32At(const std::vector<unsigned char>& bytes, std::size_t offset) {
    std::uint32_t v = 0;
    std::memcpy(&v, bytes.data() + offset, 4);
    return v;
}

/** The glTF JSON of a .gltf, or of a .glb's first chunk, parsed independently of tinygltf. */
json readGltfJson(const fs::path& path) {
    const std::vector<unsigned char> bytes = readBytes(path);
    if (bytes.size() >= 20 && u32At(bytes, 0) == 0x46546C67) {
        const std::uint32_t length = u32At(bytes, 12);
        return json::parse(bytes.begin() + 20, bytes.begin() + 20 + length);
    }
    return json::parse(bytes.begin(), bytes.end());
}

// ------------------------------------------------------------------------------------------
// Expected counts, computed from the JSON alone.

struct ExpectedCounts {
    std::uint64_t declared = 0;
    std::uint64_t emitted = 0;
    std::uint64_t prototypes = 0;
    std::uint64_t instances = 0;
};

std::uint64_t trianglesOfPrimitive(const json& gltf, const json& primitive) {
    const int mode = primitive.value("mode", 4);
    if (mode < 4 || mode > 6)
        return 0;
    std::uint64_t n = 0;
    if (primitive.contains("indices"))
        n = gltf["accessors"][primitive["indices"].get<std::size_t>()]["count"]
                    .get<std::uint64_t>();
    else if (primitive["attributes"].contains("POSITION"))
        n = gltf["accessors"][primitive["attributes"]["POSITION"].get<std::size_t>()]["count"]
                    .get<std::uint64_t>();
    if (mode == 4)
        return n / 3;
    return n >= 3 ? n - 2 : 0;
}

/** Two meshes share a prototype when everything that shapes their triangles is equal. */
std::string geometryKeyOf(const json& gltf, const json& mesh) {
    json key = json::array();
    for (const json& primitive : mesh["primitives"]) {
        json k = {
                {"mode", primitive.value("mode", 4)},
                {"indices", primitive.value("indices", -1)},
                {"attributes", primitive["attributes"]}};
        if (primitive.contains("extensions") &&
            primitive["extensions"].contains("KHR_draco_mesh_compression"))
            k["draco"] = primitive["extensions"]["KHR_draco_mesh_compression"];
        if (primitive.contains("material")) {
            const json pbr = gltf["materials"][primitive["material"].get<std::size_t>()].value(
                    "pbrMetallicRoughness", json::object());
            k["factor"] = pbr.value("baseColorFactor", json{1, 1, 1, 1});
            k["texture"] = pbr.value("baseColorTexture", json::object());
            k["texture"].erase("extensions");
        }
        key.push_back(k);
    }
    return key.dump();
}

ExpectedCounts expectedCounts(const json& gltf) {
    std::vector<std::size_t> roots;
    if (gltf.contains("scenes") && !gltf["scenes"].empty()) {
        const auto scene = gltf.value("scene", std::size_t{0});
        for (const json& n : gltf["scenes"][scene].value("nodes", json::array()))
            roots.push_back(n.get<std::size_t>());
    }
    std::map<std::size_t, std::uint64_t> instancesPerMesh;
    std::function<void(std::size_t)> walk = [&](std::size_t index) {
        const json& node = gltf["nodes"][index];
        if (node.contains("mesh")) {
            std::uint64_t copies = 1;
            if (node.contains("extensions") &&
                node["extensions"].contains("EXT_mesh_gpu_instancing")) {
                const json& attributes =
                        node["extensions"]["EXT_mesh_gpu_instancing"]["attributes"];
                copies = gltf["accessors"][attributes.begin().value().get<std::size_t>()]["count"]
                                 .get<std::uint64_t>();
            }
            instancesPerMesh[node["mesh"].get<std::size_t>()] += copies;
        }
        for (const json& child : node.value("children", json::array()))
            walk(child.get<std::size_t>());
    };
    for (std::size_t root : roots)
        walk(root);
    ExpectedCounts out;
    std::set<std::string> prototypes;
    for (const auto& [mesh, copies] : instancesPerMesh) {
        std::uint64_t triangles = 0;
        for (const json& primitive : gltf["meshes"][mesh]["primitives"])
            triangles += trianglesOfPrimitive(gltf, primitive);
        out.declared += triangles * copies;
        if (triangles > 0) {
            out.instances += copies;
            if (prototypes.insert(geometryKeyOf(gltf, gltf["meshes"][mesh])).second) {
                out.emitted += triangles;
                out.prototypes += 1;
            }
        }
    }
    return out;
}

std::string testName(const fs::path& relative) {
    std::string name = relative.string();
    for (char& c : name) {
        if (!std::isalnum(static_cast<unsigned char>(c)))
            c = '_';
    }
    return name;
}

// Runs during static initialisation (it names the parameterized tests), so it must not throw:
// without ../shared/data the list is empty and SharedDataTest says what is missing.
std::vector<std::string> validModels() {
    std::vector<std::string> out;
    for (const char* folder : {"static", "draco", "animated", "edgecases", "scanned"}) {
        std::error_code error;
        for (fs::recursive_directory_iterator it(kData / folder, error), end; !error && it != end; it.increment(error)) {
            const fs::directory_entry& entry = *it;
            const std::string ext = entry.path().extension().string();
            if (entry.is_regular_file() && (ext == ".gltf" || ext == ".glb"))
                out.push_back(fs::relative(entry.path(), kData).string());
        }
    }
    std::sort(out.begin(), out.end());
    return out;
}

TEST(SharedDataTest, TheModelsBesideTheCheckoutAreThere) {
    ASSERT_TRUE(fs::is_directory(kData)) << kData << " is missing: the tests read the models of ../shared/data "
                                                    "beside the checkout";
    EXPECT_FALSE(validModels().empty());
}

struct Imported {
    RecordingSink sink;
    Result<GltfImportReport> result = Status{ErrorCode::Internal, "not run"};
};

std::unique_ptr<Imported> importFile(const fs::path& path, GltfImportOptions options = {}) {
    auto out = std::make_unique<Imported>();
    out->result = importGltf(path, out->sink, options);
    return out;
}

bool anyWarningContains(const GltfImportReport& report, const std::string& needle) {
    return std::any_of(report.warnings.begin(), report.warnings.end(), [&](const std::string& w) {
        return w.find(needle) != std::string::npos;
    });
}

// ------------------------------------------------------------------------------------------
// Every valid model imports, with counts matching the JSON.

class GltfValidModelTest : public ::testing::TestWithParam<std::string> {};

TEST_P(GltfValidModelTest, ImportsWithCountsMatchingTheJson) {
    const fs::path path = kData / GetParam();
    const auto imported = importFile(path);
    ASSERT_TRUE(imported->result.isOk()) << imported->result.status().toString();
    const GltfImportReport& report = imported->result.value();
    const ExpectedCounts expected = expectedCounts(readGltfJson(path));

    EXPECT_GT(report.declaredTriangles, 0u);
    EXPECT_EQ(report.declaredTriangles, expected.declared);
    EXPECT_EQ(report.emittedTriangles, expected.emitted);
    EXPECT_EQ(report.prototypes, expected.prototypes);
    EXPECT_EQ(report.instances, expected.instances);
    EXPECT_EQ(imported->sink.storedTriangles(), report.emittedTriangles);
    EXPECT_EQ(imported->sink.prototypes().size(), report.prototypes);
    EXPECT_EQ(imported->sink.instances().size(), report.instances);
    EXPECT_LE(imported->sink.largestBatch(), 4096u);
    for (std::size_t p = 0; p < imported->sink.prototypes().size(); ++p)
        EXPECT_GE(imported->sink.instancesOf(static_cast<PrototypeId>(p)), 1u) << "prototype " << p;
}

INSTANTIATE_TEST_SUITE_P(
        SharedData,
        GltfValidModelTest,
        ::testing::ValuesIn(validModels()),
        [](const ::testing::TestParamInfo<std::string>& p) { return testName(p.param); });

TEST(GltfImporterTest, FindsTheSharedModels) {
    EXPECT_GE(validModels().size(), 25u); // guards against the data folder silently moving
}

// ------------------------------------------------------------------------------------------
// Hand-checked absolute numbers.

TEST(GltfImporterTest, BoxIsTwelveTrianglesOneInstanceInEveryEncoding) {
    for (const char* file :
         {"static/Box/glTF/Box.gltf",
          "static/Box/glTF-Embedded/Box.gltf",
          "draco/Box/glTF-Draco/Box.gltf"}) {
        SCOPED_TRACE(file);
        const auto imported = importFile(kData / file);
        ASSERT_TRUE(imported->result.isOk()) << imported->result.status().toString();
        EXPECT_EQ(imported->result->declaredTriangles, 12u);
        EXPECT_EQ(imported->result->emittedTriangles, 12u);
        EXPECT_EQ(imported->result->prototypes, 1u);
        EXPECT_EQ(imported->result->instances, 1u);
    }
}

TEST(GltfImporterTest, ScannedMeshesHaveTheirKnownTriangleCounts) {
    const auto skull = importFile(kData / "scanned/skull/skull.glb");
    ASSERT_TRUE(skull->result.isOk()) << skull->result.status().toString();
    EXPECT_EQ(skull->result->declaredTriangles, 100002u);
    EXPECT_EQ(skull->result->emittedTriangles, 100002u);
    EXPECT_GT(skull->sink.batches(), 20u); // streamed in batches, not one vector

    const auto bust = importFile(kData / "scanned/demosthenes/demosthenes-low-res.glb");
    ASSERT_TRUE(bust->result.isOk()) << bust->result.status().toString();
    EXPECT_EQ(bust->result->declaredTriangles, 16719u);
    EXPECT_EQ(bust->result->emittedTriangles, 16719u);
}

TEST(GltfImporterTest, SharedMeshesStayPrototypesWithManyInstances) {
    const auto imported = importFile(
            kData /
            "static/MetalRoughSpheresNoTextures/glTF-Binary/MetalRoughSpheresNoTextures.glb");
    ASSERT_TRUE(imported->result.isOk()) << imported->result.status().toString();
    const GltfImportReport& report = imported->result.value();
    EXPECT_LT(report.prototypes, report.instances);
    std::size_t reused = 0;
    for (std::size_t p = 0; p < imported->sink.prototypes().size(); ++p)
        reused += imported->sink.instancesOf(static_cast<PrototypeId>(p)) > 1 ? 1u : 0u;
    EXPECT_GT(reused, 0u);
    // Stored once, drawn many times: the instanced count dwarfs the stored one.
    EXPECT_GT(report.declaredTriangles, 10 * report.emittedTriangles);
}

TEST(GltfImporterTest, DracoModelsMatchTheirPlainTwins) {
    const std::vector<std::pair<const char*, const char*>> twins = {
            {"static/Box/glTF/Box.gltf", "draco/Box/glTF-Draco/Box.gltf"},
            {"static/CesiumMilkTruck/glTF-Binary/CesiumMilkTruck.glb",
             "draco/CesiumMilkTruck/glTF-Draco/CesiumMilkTruck.gltf"},
            {"animated/CesiumMan/glTF/CesiumMan.gltf", "draco/CesiumMan/glTF-Draco/CesiumMan.gltf"},
            {"animated/RiggedSimple/glTF-Binary/RiggedSimple.glb",
             "draco/RiggedSimple/glTF-Draco/RiggedSimple.gltf"},
            {"animated/MorphPrimitivesTest/glTF-Binary/MorphPrimitivesTest.glb",
             "draco/MorphPrimitivesTest/glTF-Draco/MorphPrimitivesTest.gltf"},
    };
    for (const auto& [plain, draco] : twins) {
        SCOPED_TRACE(draco);
        const auto a = importFile(kData / plain);
        const auto b = importFile(kData / draco);
        ASSERT_TRUE(a->result.isOk()) << a->result.status().toString();
        ASSERT_TRUE(b->result.isOk()) << b->result.status().toString();
        EXPECT_EQ(a->result->declaredTriangles, b->result->declaredTriangles);
        EXPECT_EQ(a->result->emittedTriangles, b->result->emittedTriangles);
        EXPECT_EQ(a->sink.storedTriangles(), b->sink.storedTriangles());
        EXPECT_EQ(a->result->instances, b->result->instances);
    }
}

TEST(GltfImporterTest, DracoBoxHasTheSameGeometryAsThePlainBox) {
    const auto plain = importFile(kData / "static/Box/glTF/Box.gltf");
    const auto draco = importFile(kData / "draco/Box/glTF-Draco/Box.gltf");
    ASSERT_TRUE(plain->result.isOk() && draco->result.isOk());
    // Same set of corner positions (Draco reorders vertices and may quantize slightly).
    auto corners = [](const RecordingSink& sink) {
        std::set<std::array<int, 3>> out;
        for (const auto& t : sink.prototypes().at(0).triangles) {
            for (const auto& v : t.vertices) {
                out.insert(
                        {static_cast<int>(std::lround(v.position[0] * 100)),
                         static_cast<int>(std::lround(v.position[1] * 100)),
                         static_cast<int>(std::lround(v.position[2] * 100))});
            }
        }
        return out;
    };
    EXPECT_EQ(corners(plain->sink), corners(draco->sink));
    EXPECT_EQ(corners(plain->sink).size(), 8u);
}

// ------------------------------------------------------------------------------------------
// Instancing, primitive modes, rest pose.

TEST(GltfImporterTest, GpuInstancingGivesOneInstancePerEntry) {
    const fs::path path = kData / "edgecases/SimpleInstancing/glTF-Binary/SimpleInstancing.glb";
    const json gltf = readGltfJson(path);
    std::uint64_t entries = 0;
    std::size_t instancingNodes = 0;
    for (const json& node : gltf["nodes"]) {
        if (node.contains("extensions") && node["extensions"].contains("EXT_mesh_gpu_instancing")) {
            ++instancingNodes;
            const json& attributes = node["extensions"]["EXT_mesh_gpu_instancing"]["attributes"];
            entries += gltf["accessors"][attributes["TRANSLATION"].get<std::size_t>()]["count"]
                               .get<std::uint64_t>();
        }
    }
    ASSERT_GT(instancingNodes, 0u);
    const auto imported = importFile(path);
    ASSERT_TRUE(imported->result.isOk()) << imported->result.status().toString();
    EXPECT_EQ(imported->result->instances, entries);
    EXPECT_GT(entries, instancingNodes);
    EXPECT_LT(imported->result->prototypes, imported->result->instances);
    // Distinct placements, not one transform repeated.
    std::set<std::array<float, 3>> origins;
    for (const auto& instance : imported->sink.instances())
        origins.insert(
                {instance.transform[3][0], instance.transform[3][1], instance.transform[3][2]});
    EXPECT_EQ(origins.size(), imported->sink.instances().size());
}

TEST(GltfImporterTest, PointsAndLinesAreSkippedAndNamed) {
    const auto imported =
            importFile(kData / "edgecases/MeshPrimitiveModes/glTF/MeshPrimitiveModes.gltf");
    ASSERT_TRUE(imported->result.isOk()) << imported->result.status().toString();
    EXPECT_EQ(imported->result->skippedPrimitives, 4u); // POINTS, LINES, LINE_LOOP, LINE_STRIP
    EXPECT_TRUE(anyWarningContains(*imported->result, "POINTS"));
    EXPECT_TRUE(anyWarningContains(*imported->result, "LINE_STRIP"));
}

TEST(GltfImporterTest, SkinnedAndMorphedMeshesAreTakenInRestPoseWithAWarning) {
    const auto skinned = importFile(kData / "animated/RiggedSimple/glTF-Binary/RiggedSimple.glb");
    ASSERT_TRUE(skinned->result.isOk()) << skinned->result.status().toString();
    EXPECT_TRUE(anyWarningContains(*skinned->result, "skinned"));
    const auto morphed =
            importFile(kData / "animated/AnimatedMorphCube/glTF-Binary/AnimatedMorphCube.glb");
    ASSERT_TRUE(morphed->result.isOk()) << morphed->result.status().toString();
    EXPECT_TRUE(anyWarningContains(*morphed->result, "morph"));
}

TEST(GltfImporterTest, NegativeScalesGiveMirroredInstances) {
    const fs::path path = kData / "static/NegativeScaleTest/glTF-Binary/NegativeScaleTest.glb";
    const json gltf = readGltfJson(path);
    // Expected mirror flags from the JSON: the sign of the product of scales down each chain.
    std::multiset<bool> expected;
    std::function<void(std::size_t, bool)> walk = [&](std::size_t index, bool mirrored) {
        const json& node = gltf["nodes"][index];
        if (node.contains("scale")) {
            const json& s = node["scale"];
            mirrored ^= (s[0].get<double>() * s[1].get<double>() * s[2].get<double>()) < 0.0;
        }
        ASSERT_FALSE(node.contains("matrix")) << "test assumes TRS nodes";
        if (node.contains("mesh"))
            expected.insert(mirrored);
        for (const json& child : node.value("children", json::array()))
            walk(child.get<std::size_t>(), mirrored);
    };
    for (const json& root : gltf["scenes"][gltf.value("scene", std::size_t{0})]["nodes"])
        walk(root.get<std::size_t>(), false);
    ASSERT_GT(expected.count(true), 0u);

    const auto imported = importFile(path);
    ASSERT_TRUE(imported->result.isOk()) << imported->result.status().toString();
    std::multiset<bool> actual;
    for (const auto& instance : imported->sink.instances())
        actual.insert(glm::determinant(glm::mat3(instance.transform)) < 0.0f);
    EXPECT_EQ(actual, expected);
}

// ------------------------------------------------------------------------------------------
// Small hand-written files.

std::string base64(const std::vector<unsigned char>& bytes) {
    static const char* kAlphabet =
            "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    std::size_t i = 0;
    for (; i + 2 < bytes.size(); i += 3) {
        const std::uint32_t v =
                (std::uint32_t{bytes[i]} << 16) | (std::uint32_t{bytes[i + 1]} << 8) | bytes[i + 2];
        for (int s : {18, 12, 6, 0})
            out += kAlphabet[(v >> s) & 63];
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

template <typename T>
void append(std::vector<unsigned char>& out, std::initializer_list<T> values) {
    for (T v : values) {
        unsigned char raw[sizeof(T)];
        std::memcpy(raw, &v, sizeof(T));
        out.insert(out.end(), raw, raw + sizeof(T));
    }
}

/** One triangle: 3 float positions (bytes 0-35), then 3 uint16 indices (36-41) + 2 pad bytes. */
json triangleGltf(std::initializer_list<std::uint16_t> indices = {0, 1, 2}) {
    std::vector<unsigned char> buffer;
    append<float>(buffer, {0, 0, 0, 1, 0, 0, 0, 1, 0});
    append<std::uint16_t>(buffer, indices);
    append<std::uint16_t>(buffer, {0});
    return json{
            {"asset", {{"version", "2.0"}}},
            {"scene", 0},
            {"scenes", {{{"nodes", {0}}}}},
            {"nodes", {{{"mesh", 0}}}},
            {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}}}, {"indices", 1}}}}}}},
            {"accessors",
             {{{"bufferView", 0}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"}},
              {{"bufferView", 1}, {"componentType", 5123}, {"count", 3}, {"type", "SCALAR"}}}},
            {"bufferViews",
             {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 36}},
              {{"buffer", 0}, {"byteOffset", 36}, {"byteLength", 6}}}},
            {"buffers",
             {{{"byteLength", buffer.size()},
               {"uri", "data:application/octet-stream;base64," + base64(buffer)}}}}};
}

fs::path writeGltf(const std::string& name, const json& gltf) {
    const fs::path path = tempDir() / name;
    writeText(path, gltf.dump(1));
    return path;
}

TEST(GltfImporterTest, HandWrittenTriangleImports) {
    const auto imported = importFile(writeGltf("triangle.gltf", triangleGltf()));
    ASSERT_TRUE(imported->result.isOk()) << imported->result.status().toString();
    EXPECT_EQ(imported->result->emittedTriangles, 1u);
    const auto& v = imported->sink.prototypes().at(0).triangles.at(0).vertices;
    EXPECT_EQ(v[1].position[0], 1.0f);
    EXPECT_EQ(v[2].position[1], 1.0f);
    // No material: white.
    EXPECT_EQ(v[0].color, (std::array<std::uint8_t, 4>{255, 255, 255, 255}));
}

TEST(GltfImporterTest, MeshReferencedByTwoNodesIsOnePrototypeWithTwoInstances) {
    json gltf = triangleGltf();
    gltf["nodes"] = {
            {{"mesh", 0}, {"translation", {5, 0, 0}}}, {{"mesh", 0}, {"translation", {0, 7, 0}}}};
    gltf["scenes"][0]["nodes"] = {0, 1};
    const auto imported = importFile(writeGltf("two_nodes.gltf", gltf));
    ASSERT_TRUE(imported->result.isOk()) << imported->result.status().toString();
    EXPECT_EQ(imported->result->prototypes, 1u);
    EXPECT_EQ(imported->result->instances, 2u);
    EXPECT_EQ(imported->result->emittedTriangles, 1u);
    EXPECT_EQ(imported->result->declaredTriangles, 2u);
    ASSERT_EQ(imported->sink.instances().size(), 2u);
    EXPECT_EQ(imported->sink.instances()[0].transform[3], glm::vec4(5, 0, 0, 1));
    EXPECT_EQ(imported->sink.instances()[1].transform[3], glm::vec4(0, 7, 0, 1));
}

TEST(GltfImporterTest, ParentTransformsCompose) {
    json gltf = triangleGltf();
    gltf["nodes"] = {
            {{"children", {1}}, {"translation", {1, 2, 3}}, {"scale", {2, 2, 2}}},
            {{"mesh", 0}, {"matrix", {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 10, 0, 0, 1}}}};
    const auto imported = importFile(writeGltf("hierarchy.gltf", gltf));
    ASSERT_TRUE(imported->result.isOk()) << imported->result.status().toString();
    ASSERT_EQ(imported->sink.instances().size(), 1u);
    const glm::mat4& m = imported->sink.instances()[0].transform;
    EXPECT_EQ(m[3], glm::vec4(21, 2, 3, 1)); // parent T * S applied to the child's translation
    EXPECT_EQ(m[0][0], 2.0f);
}

TEST(GltfImporterTest, BaseColorFactorAndVertexColorsMultiply) {
    json gltf = triangleGltf();
    std::vector<unsigned char> colors;
    append<float>(colors, {1, 1, 1, 0.5f, 0.5f, 0.5f, 1, 0, 0});
    gltf["buffers"].push_back(
            {{"byteLength", colors.size()},
             {"uri", "data:application/octet-stream;base64," + base64(colors)}});
    gltf["bufferViews"].push_back({{"buffer", 1}, {"byteLength", colors.size()}});
    gltf["accessors"].push_back(
            {{"bufferView", 2}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"}});
    gltf["meshes"][0]["primitives"][0]["attributes"]["COLOR_0"] = 2;
    gltf["meshes"][0]["primitives"][0]["material"] = 0;
    gltf["materials"] = {{{"pbrMetallicRoughness", {{"baseColorFactor", {0.5, 0.25, 1.0, 0.75}}}}}};
    const auto imported = importFile(writeGltf("colors.gltf", gltf));
    ASSERT_TRUE(imported->result.isOk()) << imported->result.status().toString();
    const auto& v = imported->sink.prototypes().at(0).triangles.at(0).vertices;
    using storage::linearToSrgb8;
    using storage::toUnorm8;
    EXPECT_EQ(
            v[0].color,
            (std::array<std::uint8_t, 4>{
                    linearToSrgb8(0.5f),
                    linearToSrgb8(0.25f),
                    linearToSrgb8(1.0f),
                    toUnorm8(0.75f)}));
    EXPECT_EQ(
            v[1].color,
            (std::array<std::uint8_t, 4>{
                    linearToSrgb8(0.25f),
                    linearToSrgb8(0.125f),
                    linearToSrgb8(0.5f),
                    toUnorm8(0.75f)}));
    EXPECT_EQ(
            v[2].color,
            (std::array<std::uint8_t, 4>{
                    linearToSrgb8(0.5f),
                    linearToSrgb8(0.0f),
                    linearToSrgb8(0.0f),
                    toUnorm8(0.75f)}));
}

TEST(GltfImporterTest, RealModelBaseColorFactorIsApplied) {
    // MetalRoughSpheresNoTextures: every material has a baseColorFactor and no texture, so the
    // colours written must be exactly the factors found in the JSON.
    const fs::path path =
            kData /
            "static/MetalRoughSpheresNoTextures/glTF-Binary/MetalRoughSpheresNoTextures.glb";
    const json gltf = readGltfJson(path);
    std::set<std::array<std::uint8_t, 4>> expected = {{255, 255, 255, 255}}; // no material
    std::set<std::array<std::uint8_t, 4>> factors;
    for (const json& material : gltf["materials"]) {
        const json f = material.value("pbrMetallicRoughness", json::object())
                               .value("baseColorFactor", json{1, 1, 1, 1});
        factors.insert(
                {storage::linearToSrgb8(f[0].get<float>()),
                 storage::linearToSrgb8(f[1].get<float>()),
                 storage::linearToSrgb8(f[2].get<float>()),
                 storage::toUnorm8(f[3].get<float>())});
    }
    expected.insert(factors.begin(), factors.end());
    ASSERT_GE(factors.size(), 2u);
    const auto imported = importFile(path);
    ASSERT_TRUE(imported->result.isOk()) << imported->result.status().toString();
    std::set<std::array<std::uint8_t, 4>> actual;
    for (const auto& prototype : imported->sink.prototypes()) {
        for (const auto& t : prototype.triangles)
            actual.insert(t.vertices[0].color);
    }
    for (const auto& factor : factors)
        EXPECT_TRUE(actual.count(factor))
                << int(factor[0]) << "," << int(factor[1]) << "," << int(factor[2]);
    for (const auto& color : actual)
        EXPECT_TRUE(expected.count(color))
                << int(color[0]) << "," << int(color[1]) << "," << int(color[2]);
}

TEST(GltfImporterTest, AvocadoTextureColoursTheVertices) {
    const auto imported = importFile(kData / "static/Avocado/glTF/Avocado.gltf");
    ASSERT_TRUE(imported->result.isOk()) << imported->result.status().toString();
    std::set<std::array<std::uint8_t, 4>> colors;
    std::size_t white = 0;
    std::size_t greenish = 0;
    for (const auto& t : imported->sink.prototypes().at(0).triangles) {
        for (const auto& v : t.vertices) {
            colors.insert(v.color);
            white += v.color == std::array<std::uint8_t, 4>{255, 255, 255, 255} ? 1u : 0u;
            greenish += v.color[1] > v.color[2] ? 1u : 0u;
        }
    }
    EXPECT_EQ(white, 0u);
    EXPECT_GT(colors.size(), 50u);
    EXPECT_GT(greenish, imported->result->emittedTriangles); // an avocado is mostly green/brown
}

TEST(GltfImporterTest, CameraNodesAreReported) {
    json gltf = triangleGltf();
    const double s = std::sqrt(0.5);
    gltf["cameras"] = {
            {{"type", "perspective"},
             {"name", "main"},
             {"perspective",
              {{"yfov", 0.7}, {"znear", 0.1}, {"zfar", 100.0}, {"aspectRatio", 1.5}}}},
            {{"type", "orthographic"},
             {"orthographic", {{"xmag", 2.0}, {"ymag", 3.0}, {"znear", 0.5}, {"zfar", 50.0}}}}};
    gltf["nodes"] = {
            {{"mesh", 0}},
            {{"translation", {10, 0, 0}}, {"children", {2, 3}}},
            // rotated +90 degrees about Y: -Z turns into -X
            {{"camera", 0}, {"translation", {1, 2, 3}}, {"rotation", {0, s, 0, s}}},
            {{"camera", 1}}};
    gltf["scenes"][0]["nodes"] = {0, 1};
    const auto imported = importFile(writeGltf("camera.gltf", gltf));
    ASSERT_TRUE(imported->result.isOk()) << imported->result.status().toString();
    const auto& cameras = imported->result->cameras;
    ASSERT_EQ(cameras.size(), 2u);
    const GltfCamera& c = cameras[0];
    EXPECT_EQ(c.name, "main");
    EXPECT_TRUE(c.perspective);
    EXPECT_NEAR(c.eye.x, 11.0, 1e-5);
    EXPECT_NEAR(c.eye.y, 2.0, 1e-5);
    EXPECT_NEAR(c.eye.z, 3.0, 1e-5);
    EXPECT_NEAR(c.forward.x, -1.0f, 1e-5f);
    EXPECT_NEAR(c.forward.y, 0.0f, 1e-5f);
    EXPECT_NEAR(c.forward.z, 0.0f, 1e-5f);
    EXPECT_NEAR(c.up.y, 1.0f, 1e-5f);
    EXPECT_FLOAT_EQ(c.yfovRadians, 0.7f);
    EXPECT_FLOAT_EQ(c.aspectRatio, 1.5f);
    EXPECT_FLOAT_EQ(c.znear, 0.1f);
    EXPECT_FLOAT_EQ(c.zfar, 100.0f);
    const GltfCamera& o = cameras[1];
    EXPECT_FALSE(o.perspective);
    EXPECT_EQ(o.eye, glm::dvec3(10, 0, 0));
    EXPECT_EQ(o.forward, glm::vec3(0, 0, -1));
    EXPECT_FLOAT_EQ(o.xmag, 2.0f);
    EXPECT_FLOAT_EQ(o.ymag, 3.0f);
}

TEST(GltfImporterTest, SceneOptionSelectsTheScene) {
    json gltf = triangleGltf();
    gltf["nodes"] = {{{"mesh", 0}}, {{"mesh", 0}}, {{"mesh", 0}}};
    gltf["scenes"] = {{{"nodes", {0}}}, {{"nodes", {1, 2}}}};
    const fs::path path = writeGltf("scenes.gltf", gltf);
    EXPECT_EQ(importFile(path)->result->instances, 1u);
    GltfImportOptions second;
    second.scene = 1;
    EXPECT_EQ(importFile(path, second)->result->instances, 2u);
    GltfImportOptions missing;
    missing.scene = 2;
    EXPECT_EQ(importFile(path, missing)->result.status().code(), ErrorCode::InvalidArgument);
}

// ------------------------------------------------------------------------------------------
// Refusals of hand-written broken files.

void expectRefused(const fs::path& path, ErrorCode code, const std::string& needle) {
    const auto imported = importFile(path);
    ASSERT_FALSE(imported->result.isOk()) << path;
    EXPECT_EQ(imported->result.status().code(), code) << imported->result.status().toString();
    EXPECT_NE(imported->result.status().message().find(needle), std::string::npos)
            << imported->result.status().toString();
}

TEST(GltfImporterTest, AccessorPastItsBufferViewIsRefused) {
    json gltf = triangleGltf();
    gltf["accessors"][0]["count"] = 4; // 48 bytes from a 36-byte view
    expectRefused(writeGltf("accessor_oob.gltf", gltf), ErrorCode::InvalidInput, "accessor 0");
}

TEST(GltfImporterTest, AccessorStrideWalkPastTheViewIsRefused) {
    json gltf = triangleGltf();
    gltf["bufferViews"][0]["byteStride"] = 16; // 2 * 16 + 12 = 44 > 36
    expectRefused(writeGltf("stride_oob.gltf", gltf), ErrorCode::InvalidInput, "accessor 0");
}

TEST(GltfImporterTest, StrideSmallerThanAnElementIsRefused) {
    json gltf = triangleGltf();
    gltf["bufferViews"][0]["byteStride"] = 8; // VEC3 float needs 12
    expectRefused(
            writeGltf("small_stride.gltf", gltf),
            ErrorCode::InvalidInput,
            "accessor 0: byteStride 8");
}

TEST(GltfImporterTest, BufferViewPastItsBufferIsRefused) {
    json gltf = triangleGltf();
    gltf["bufferViews"][1]["byteLength"] = 60;
    expectRefused(writeGltf("view_oob.gltf", gltf), ErrorCode::InvalidInput, "bufferView 1");
}

TEST(GltfImporterTest, IndexPastTheVerticesIsRefused) {
    expectRefused(
            writeGltf("index_oob.gltf", triangleGltf({0, 1, 3})),
            ErrorCode::InvalidInput,
            "index 3");
}

TEST(GltfImporterTest, UnsupportedRequiredExtensionIsNamed) {
    json gltf = triangleGltf();
    gltf["extensionsUsed"] = {"KHR_mesh_quantization", "EXT_made_up"};
    gltf["extensionsRequired"] = {"KHR_mesh_quantization", "EXT_made_up"};
    expectRefused(
            writeGltf("required_ext.gltf", gltf),
            ErrorCode::Unsupported,
            "required extension EXT_made_up is not supported");
}

TEST(GltfImporterTest, NodeLoopAndSecondParentAreRefused) {
    json loop = triangleGltf();
    loop["nodes"] = {{{"mesh", 0}, {"children", {1}}}, {{"children", {2}}}, {{"children", {1}}}};
    expectRefused(writeGltf("loop.gltf", loop), ErrorCode::InvalidInput, "loop");
    json twoParents = triangleGltf();
    twoParents["nodes"] = {{{"children", {2}}}, {{"children", {2}}}, {{"mesh", 0}}};
    twoParents["scenes"][0]["nodes"] = {0, 1};
    expectRefused(writeGltf("two_parents.gltf", twoParents), ErrorCode::InvalidInput, "node 2");
}

TEST(GltfImporterTest, UnequalAttributeCountsAreRefused) {
    json gltf = triangleGltf();
    gltf["accessors"].push_back(
            {{"bufferView", 0}, {"componentType", 5126}, {"count", 2}, {"type", "VEC3"}});
    gltf["meshes"][0]["primitives"][0]["attributes"]["NORMAL"] = 2;
    expectRefused(writeGltf("unequal.gltf", gltf), ErrorCode::InvalidInput, "mesh 0 primitive 0");
}

TEST(GltfImporterTest, MissingFileIsNotFound) {
    const auto imported = importFile(tempDir() / "does_not_exist.gltf");
    EXPECT_EQ(imported->result.status().code(), ErrorCode::NotFound);
}

TEST(GltfImporterTest, TruncatedGlbFailsCleanlyAtEveryLength) {
    const std::vector<unsigned char> whole =
            readBytes(kData / "edgecases/SimpleInstancing/glTF-Binary/SimpleInstancing.glb");
    ASSERT_GT(whole.size(), 100u);
    std::vector<std::size_t> lengths = {
            0,
            1,
            4,
            11,
            12,
            16,
            19,
            20,
            21,
            64,
            whole.size() / 2,
            whole.size() - 4,
            whole.size() - 1};
    for (std::size_t n = 24; n < whole.size(); n += whole.size() / 17)
        lengths.push_back(n);
    for (std::size_t length : lengths) {
        for (bool patchHeader : {false, true}) {
            SCOPED_TRACE(std::to_string(length) + (patchHeader ? " patched" : ""));
            std::vector<unsigned char> cut(
                    whole.begin(), whole.begin() + static_cast<std::ptrdiff_t>(length));
            if (patchHeader && cut.size() >= 12) {
                // Make the header agree with the cut so the chunk parsing is what fails.
                const auto size = static_cast<std::uint32_t>(cut.size());
                std::memcpy(cut.data() + 8, &size, 4);
            }
            const fs::path path = tempDir() / "truncated.glb";
            writeBytes(path, cut);
            RecordingSink sink;
            const auto result = importGltf(path, sink);
            ASSERT_FALSE(result.isOk());
            EXPECT_FALSE(result.status().message().empty());
        }
    }
}

// ------------------------------------------------------------------------------------------
// The invalid corpus: every file has an expectation; a change in behaviour fails a test.

enum class Expect { Refuse, Load };

struct InvalidCase {
    const char* path; ///< relative to shared/data/invalid
    Expect expect;
};

// Refuse: the error breaks something the importer reads (GLB framing, JSON, buffers,
// bufferViews, accessors referenced by meshes, meshes, nodes, scenes, index values).
// Load: the error is only in data we ignore (animation, skins, morph targets, joint/weight
// values, min/max bounds, NaN vertex values that the sink drops) or tinygltf's own
// "expected to load" regression files.
const std::vector<InvalidCase> kInvalidCases = {
        {"gltf-validator/glb/chunk_too_big.glb", Expect::Refuse},
        {"gltf-validator/glb/empty_file.glb", Expect::Refuse},
        {"gltf-validator/glb/invalid_magic.glb", Expect::Refuse},
        {"gltf-validator/glb/invalid_version.glb", Expect::Refuse},
        {"gltf-validator/glb/length_mismatch.glb", Expect::Refuse},
        {"gltf-validator/glb/truncated_chunk_data.glb", Expect::Refuse},
        {"gltf-validator/glb/truncated_chunk_header.glb", Expect::Refuse},
        {"gltf-validator/glb/only_header.glb", Expect::Refuse},
        {"gltf-validator/glb/no_header.glb", Expect::Refuse},
        {"gltf-validator/glb/unaligned_chunk.glb", Expect::Refuse},
        {"gltf-validator/glb/two_bin_chunks.glb", Expect::Refuse},
        {"gltf-validator/glb/zero_length.glb", Expect::Refuse},
        {"gltf-validator/glb/invalid_json_chunk.glb", Expect::Refuse},
        {"gltf-validator/json/invalid_syntax.gltf", Expect::Refuse},
        {"gltf-validator/json/empty_file.gltf", Expect::Refuse},
        {"gltf-validator/json/invalid_object.gltf", Expect::Refuse},
        {"gltf-validator/json/bom.gltf", Expect::Refuse},
        {"gltf-validator/buffer/wrong_bytelength.glb", Expect::Refuse},
        {"gltf-validator/buffer/not_found.gltf", Expect::Refuse},
        {"gltf-validator/buffer/invalid_uri_data.gltf", Expect::Refuse},
        {"gltf-validator/buffer/invalid_uri_data_bytelength.gltf", Expect::Refuse},
        {"gltf-validator/buffer/no_bin_chunk.glb", Expect::Refuse},
        {"gltf-validator/buffer_view/invalid_length.gltf", Expect::Refuse},
        {"gltf-validator/buffer_view/unresolved_buffer.gltf", Expect::Refuse},
        {"gltf-validator/buffer_view/invalid_stride_too_big.gltf", Expect::Refuse},
        {"gltf-validator/accessor/alignment.gltf", Expect::Refuse},
        {"gltf-validator/accessor/unresolved_bufferviews.gltf", Expect::Refuse},
        {"gltf-validator/accessor/invalid_sparse_count_and_stride.gltf", Expect::Refuse},
        {"gltf-validator/accessor/small_stride.gltf", Expect::Refuse},
        {"gltf-validator/accessor_data/out_of_range_elements_uint16.gltf", Expect::Load},
        {"gltf-validator/accessor_data/invalid_elements_float.gltf", Expect::Load},
        {"gltf-validator/mesh_data/index_buffer_oob.gltf", Expect::Refuse},
        {"gltf-validator/mesh_data/joints_weights_complex.gltf", Expect::Load},
        {"gltf-validator/mesh_data/joints_no_weights.gltf", Expect::Refuse},
        {"gltf-validator/mesh/unresolved_positions.gltf", Expect::Refuse},
        {"gltf-validator/mesh/accessor_unequal_count.gltf", Expect::Refuse},
        {"gltf-validator/mesh/morph_attribute_invalid_count.gltf", Expect::Load},
        {"gltf-validator/mesh/morph_unequal_targets_count.gltf", Expect::Load},
        {"gltf-validator/mesh/unresolved_indices.gltf", Expect::Refuse},
        {"gltf-validator/node/node_loop.gltf", Expect::Refuse},
        {"gltf-validator/node/node_loop_scene.gltf", Expect::Refuse},
        {"gltf-validator/node/infinite_transform.gltf", Expect::Refuse},
        {"gltf-validator/node/unresolved_child_node.gltf", Expect::Refuse},
        {"gltf-validator/node/node_parent_override.gltf", Expect::Refuse},
        {"gltf-validator/skin/ibm_invalid_count.gltf", Expect::Load},
        {"gltf-validator/skin/unresolved_joint.gltf", Expect::Load},
        {"gltf-validator/skin_data/invalid_ibm.gltf", Expect::Load},
        {"gltf-validator/animation/unresolved_sampler_input.gltf", Expect::Load},
        {"gltf-validator/animation/sampler_output_count_invalid.gltf", Expect::Load},
        {"gltf-validator/animation_data/invalid_input_values.gltf", Expect::Load},
        {"gltf-validator/scene/unresolved_node.gltf", Expect::Refuse},
        {"tinygltf/models/BoundsChecking/integer-out-of-bounds.gltf", Expect::Refuse},
        {"tinygltf/models/BoundsChecking/invalid-buffer-index.gltf", Expect::Refuse},
        {"tinygltf/models/BoundsChecking/invalid-buffer-view-index.gltf", Expect::Refuse},
        {"tinygltf/models/BoundsChecking/invalid-primitive-indices.gltf", Expect::Refuse},
        {"tinygltf/tests/issue-416.gltf", Expect::Load},
        {"tinygltf/tests/issue-492.glb", Expect::Load},
        {"tinygltf/models/regression/zero-sized-bin-chunk-issue-440.glb", Expect::Load},
        {"tinygltf/models/regression/unassigned-skeleton.gltf", Expect::Load},
};

class GltfInvalidCorpusTest : public ::testing::TestWithParam<InvalidCase> {};

TEST_P(GltfInvalidCorpusTest, BehavesAsExpected) {
    const InvalidCase& c = GetParam();
    const auto imported = importFile(kData / "invalid" / c.path);
    if (c.expect == Expect::Refuse) {
        ASSERT_FALSE(imported->result.isOk()) << c.path << " loaded but must be refused";
        EXPECT_FALSE(imported->result.status().message().empty());
        EXPECT_NE(imported->result.status().code(), ErrorCode::Internal)
                << imported->result.status().toString();
    } else {
        EXPECT_TRUE(imported->result.isOk()) << imported->result.status().toString();
    }
}

INSTANTIATE_TEST_SUITE_P(
        SharedData,
        GltfInvalidCorpusTest,
        ::testing::ValuesIn(kInvalidCases),
        [](const ::testing::TestParamInfo<InvalidCase>& p) { return testName(p.param.path); });

TEST(GltfInvalidCorpusTest, TableCoversEveryFileOfTheCorpus) {
    std::set<std::string> table;
    for (const InvalidCase& c : kInvalidCases)
        table.insert(c.path);
    std::set<std::string> listed;
    std::ifstream tsv(kData / "invalid/expected.tsv");
    std::string line;
    std::getline(tsv, line); // header
    while (std::getline(tsv, line)) {
        const std::string path = line.substr(0, line.find('\t'));
        if (!path.empty())
            listed.insert(path.substr(std::string("invalid/").size()));
    }
    std::set<std::string> onDisk;
    for (const auto& entry : fs::recursive_directory_iterator(kData / "invalid")) {
        const std::string ext = entry.path().extension().string();
        if (ext == ".gltf" || ext == ".glb")
            onDisk.insert(fs::relative(entry.path(), kData / "invalid").string());
    }
    EXPECT_EQ(table, listed);
    EXPECT_EQ(table, onDisk);
}

// ------------------------------------------------------------------------------------------
// TextureSampler (private to the importer).

TEST(TextureSamplerTest, WrapModesAtTheEdges) {
    // 2x1: black | white (sRGB 0 and 255 are linear 0 and 1).
    std::vector<std::uint8_t> texels = {0, 0, 0, 255, 255, 255, 255, 255};
    TextureSampler repeat(2, 1, texels, WrapMode::Repeat, WrapMode::Repeat);
    TextureSampler clamp(2, 1, texels, WrapMode::ClampToEdge, WrapMode::ClampToEdge);
    TextureSampler mirror(2, 1, texels, WrapMode::MirroredRepeat, WrapMode::MirroredRepeat);
    // Texel centres.
    EXPECT_FLOAT_EQ(repeat.sample({0.25f, 0.5f}).r, 0.0f);
    EXPECT_FLOAT_EQ(repeat.sample({0.75f, 0.5f}).r, 1.0f);
    // u = 0 lies between the last texel (wrapped) and the first: repeat blends, clamp does not.
    EXPECT_FLOAT_EQ(repeat.sample({0.0f, 0.5f}).r, 0.5f);
    EXPECT_FLOAT_EQ(clamp.sample({0.0f, 0.5f}).r, 0.0f);
    EXPECT_FLOAT_EQ(mirror.sample({0.0f, 0.5f}).r, 0.0f);
    // Far outside: repeat has period 1, mirror period 2, clamp saturates.
    EXPECT_FLOAT_EQ(repeat.sample({3.25f, 0.5f}).r, 0.0f);
    EXPECT_FLOAT_EQ(mirror.sample({1.25f, 0.5f}).r, 1.0f);
    EXPECT_FLOAT_EQ(clamp.sample({-7.0f, 0.5f}).r, 0.0f);
    EXPECT_FLOAT_EQ(clamp.sample({9.0f, 0.5f}).r, 1.0f);
    // Non-finite coordinates do not crash.
    EXPECT_TRUE(std::isfinite(repeat.sample({NAN, INFINITY}).r));
}

TEST(TextureSamplerTest, FiltersInLinearSpace) {
    // sRGB 188 is about linear 0.5; blending black and white in linear space gives 0.5, which
    // is sRGB 188, not 128.
    std::vector<std::uint8_t> texels = {0, 0, 0, 255, 255, 255, 255, 255};
    TextureSampler clamp(2, 1, texels, WrapMode::ClampToEdge, WrapMode::ClampToEdge);
    EXPECT_NEAR(clamp.sample({0.5f, 0.5f}).r, 0.5f, 1e-6f);
    EXPECT_NEAR(srgb8ToLinear(188), 0.5f, 0.005f);
    EXPECT_FLOAT_EQ(srgb8ToLinear(255), 1.0f);
}

} // namespace
} // namespace ff::builder
