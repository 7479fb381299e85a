#include "CountingSink.h"
#include "RecordingSink.h"

#include <ff/builder/Generators.h>
#include <ff/storage/VertexCodec.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <ostream>
#include <set>
#include <string>
#include <vector>

namespace ff::builder {
namespace {

using test::CountingSink;

GeneratorSpec specOf(const std::string& text) {
    Result<GeneratorSpec> spec = parseGeneratorSpec(text);
    EXPECT_TRUE(spec.isOk()) << text << ": " << spec.status().toString();
    return spec.isOk() ? spec.value() : GeneratorSpec{};
}

/** Runs `text` into `sink`, failing the test on error. */
GeneratorReport run(const std::string& text, CountingSink& sink) {
    Result<GeneratorReport> report = runGenerator(specOf(text), sink);
    EXPECT_TRUE(report.isOk()) << text << ": " << report.status().toString();
    return report.isOk() ? report.value() : GeneratorReport{};
}

/** The Status of running `text`, which must parse. */
Status failureOf(const std::string& text) {
    CountingSink sink;
    return runGenerator(specOf(text), sink).status();
}

void expectReportMatchesSink(const GeneratorReport& report, const CountingSink& sink) {
    EXPECT_EQ(report.storedTriangles, sink.triangleCount);
    EXPECT_EQ(report.prototypes, sink.prototypes.size());
    EXPECT_EQ(report.instances, sink.instances.size());
    std::uint64_t drawn = 0;
    for (const CountingSink::Instance& instance : sink.instances)
        drawn += sink.prototypes[instance.prototype].triangles;
    EXPECT_EQ(report.triangles, drawn);
}

glm::vec3 translationOf(const glm::mat4& m) {
    return glm::vec3(m[3]);
}
float uniformScaleOf(const glm::mat4& m) {
    return glm::length(glm::vec3(m[0]));
}

// ---------------------------------------------------------------------------------------------

TEST(GeneratorSpecTest, ParsesNameAndParameters) {
    const GeneratorSpec spec = specOf("forest:trees=16,seed=3");
    EXPECT_EQ(spec.name, "forest");
    ASSERT_EQ(spec.params.size(), 2u);
    EXPECT_EQ(spec.params.at("trees"), "16");
    EXPECT_EQ(spec.params.at("seed"), "3");
}

TEST(GeneratorSpecTest, BareNameHasNoParameters) {
    const GeneratorSpec spec = specOf("terrain");
    EXPECT_EQ(spec.name, "terrain");
    EXPECT_TRUE(spec.params.empty());
}

TEST(GeneratorSpecTest, RejectsMalformedSpecs) {
    for (const char* bad :
         {"",
          ":trees=4",
          "forest:",
          "forest:trees",
          "forest:trees=",
          "forest:=4",
          "forest:trees=4,",
          "forest:trees=4,,seed=1",
          "forest:trees=4,trees=16",
          "for est:trees=4",
          "forest:tr ees=4"}) {
        const Result<GeneratorSpec> spec = parseGeneratorSpec(bad);
        ASSERT_FALSE(spec.isOk()) << "accepted '" << bad << "'";
        EXPECT_EQ(spec.status().code(), ErrorCode::InvalidArgument) << bad;
    }
}

TEST(GeneratorCatalogTest, ListsEveryGeneratorWithDocumentedParameters) {
    std::set<std::string> names;
    for (const GeneratorInfo& info : generatorCatalog()) {
        names.insert(info.name);
        EXPECT_FALSE(info.summary.empty()) << info.name;
        EXPECT_FALSE(info.params.empty()) << info.name;
        for (const auto& [key, help] : info.params) {
            EXPECT_FALSE(key.empty()) << info.name;
            // "default: meaning"
            const std::size_t colon = help.find(": ");
            EXPECT_NE(colon, std::string::npos) << info.name << "." << key << ": " << help;
            EXPECT_GT(colon, 0u) << info.name << "." << key;
        }
    }
    EXPECT_EQ(names, (std::set<std::string>{"forest", "terrain", "molecule", "blinds", "sphere", "city", "cathedral", "isosurface"}));
}

TEST(GeneratorCatalogTest, CatalogDefaultsAreAccepted) {
    // Every documented default, passed explicitly, must be valid (checked on cheap generators
    // with the expensive count parameter kept small).
    for (const GeneratorInfo& info : generatorCatalog()) {
        std::string spec = info.name + ":";
        for (const auto& [key, help] : info.params) {
            const std::string value = help.substr(0, help.find(": "));
            const bool isSize = key == "triangles" || key == "spheres" || key == "trees" || key == "resolution";
            const std::string small = key == "triangles" ? "1000" : (key == "resolution" ? "16" : "4");
            spec += key + "=" + (isSize ? small : value) + ",";
        }
        spec.pop_back();
        CountingSink sink;
        run(spec, sink);
    }
}

// ---------------------------------------------------------------------------------------------

TEST(GeneratorsTest, RejectsUnknownGenerator) {
    const Status status = failureOf("ziggurat");
    EXPECT_EQ(status.code(), ErrorCode::InvalidArgument);
    EXPECT_NE(status.message().find("ziggurat"), std::string::npos) << status.toString();
}

TEST(GeneratorsTest, RejectsBadParametersNamingTheKey) {
    const std::map<std::string, std::string> cases = {
            {"forest:tres=16", "tres"},                              // unknown key
            {"forest:trees=3", "trees"},                             // not a power of 4
            {"forest:trees=0", "trees"},                             // out of range
            {"forest:trees=2", "trees"},                             // power of 2, not of 4
            {"forest:trees=8", "trees"},                             // power of 2, not of 4
            {"forest:seed=-1", "seed"},                              // negative
            {"terrain:triangles=lots", "triangles"},                 // non-numeric
            {"terrain:triangles=12x", "triangles"},                  // trailing junk
            {"terrain:triangles=99999999999999999999", "triangles"}, // overflow
            {"molecule:spheres=0", "spheres"},
            {"molecule:triangles_per_sphere=3", "triangles_per_sphere"},
            {"blinds:spacing=nan", "spacing"},
            {"blinds:thickness=0.5", "thickness"}, // thicker than the default spacing
            {"blinds:tilt=90", "tilt"},
            {"blinds:seed=1", "seed"}, // blinds have no seed
    };
    for (const auto& [text, key] : cases) {
        const Status status = failureOf(text);
        EXPECT_EQ(status.code(), ErrorCode::InvalidArgument) << text << ": " << status.toString();
        EXPECT_NE(status.message().find("'" + key + "'"), std::string::npos)
                << text << ": " << status.toString();
    }
}

TEST(GeneratorsTest, ReturnsTheSinksError) {
    CountingSink sink;
    sink.failAfterBatches(1);
    const Result<GeneratorReport> report = runGenerator(specOf("terrain:triangles=20000"), sink);
    ASSERT_FALSE(report.isOk());
    EXPECT_EQ(report.status().code(), ErrorCode::IoError);
}

struct GoldenScene {
    const char* spec;
    std::uint64_t triangleHash; ///< FNV-1a 64 of every triangle byte, in order
    std::uint64_t instanceHash; ///< FNV-1a 64 of every (prototype, transform)
};

void PrintTo(const GoldenScene& scene, std::ostream* out) {
    *out << scene.spec;
}

class GeneratorDeterminismTest : public ::testing::TestWithParam<GoldenScene> {};

TEST_P(GeneratorDeterminismTest, SameSpecGivesIdenticalBytes) {
    CountingSink first;
    CountingSink second;
    run(GetParam().spec, first);
    run(GetParam().spec, second);
    EXPECT_GT(first.triangleCount, 0u);
    EXPECT_EQ(first.triangleCount, second.triangleCount);
    EXPECT_EQ(first.triangleHash, second.triangleHash);
    EXPECT_EQ(first.instanceHash, second.instanceHash);
}

TEST_P(GeneratorDeterminismTest, MatchesTheBytesRecordedOnTheReferenceMachine) {
    // Pins "the same triangles on every machine": the hashes were recorded on x86-64 Debian 12
    // (GCC 12, Debug and Release). A deliberate change to a generator, or to the triangle
    // packing in ff_storage (VertexCodec), must update these constants; anything else that
    // moves them (compiler, libm, FMA contraction, platform) is a determinism bug.
    CountingSink sink;
    run(GetParam().spec, sink);
    EXPECT_EQ(sink.triangleHash, GetParam().triangleHash)
            << std::hex << "triangle bytes changed: 0x" << sink.triangleHash;
    EXPECT_EQ(sink.instanceHash, GetParam().instanceHash)
            << std::hex << "instance bytes changed: 0x" << sink.instanceHash;
}

INSTANTIATE_TEST_SUITE_P(
        AllGenerators,
        GeneratorDeterminismTest,
        ::testing::Values(
                GoldenScene{"forest:trees=4,seed=7", 0x54974393e9305d85ull, 0x8334191f1c1c1e85ull},
                GoldenScene{
                        "terrain:triangles=30000,seed=7",
                        0x3f24114e153c0c27ull,
                        0xd6e975053c6d83d5ull},
                GoldenScene{
                        "molecule:spheres=300,seed=7",
                        0xf1add161813ba4e9ull,
                        0x412069a3fb9e5606ull},
                GoldenScene{
                        "blinds:slabs=20,tilt=30", 0x05b6126a4f525d95ull, 0xd6e975053c6d83d5ull},
                GoldenScene{"sphere:triangles=2000,radius=3", 0xe25d855477140997ull, 0xd6e975053c6d83d5ull},
                GoldenScene{"city:blocks=3,floors=2,items=2,seed=7", 0xd2009451b99c759dull, 0xefcbbc213fa8a5a4ull},
                GoldenScene{"cathedral:bays=3", 0x010e54938007ffd9ull, 0xd6e975053c6d83d5ull},
                GoldenScene{"isosurface:resolution=24,seed=3", 0x81f0ae21111f4839ull, 0xd6e975053c6d83d5ull}),
        [](const ::testing::TestParamInfo<GoldenScene>& param) {
            const std::string spec = param.param.spec;
            return spec.substr(0, spec.find(':'));
        });

TEST(GeneratorsTest, SeedChangesTheScene) {
    for (const char* base : {"forest:trees=4", "terrain:triangles=5000", "molecule:spheres=50"}) {
        CountingSink a;
        CountingSink b;
        run(std::string(base) + ",seed=1", a);
        run(std::string(base) + ",seed=2", b);
        EXPECT_EQ(a.triangleCount, b.triangleCount) << base;
        EXPECT_TRUE(a.triangleHash != b.triangleHash || a.instanceHash != b.instanceHash) << base;
    }
}

// ---------------------------------------------------------------------------------------------

TEST(ForestGeneratorTest, SixteenTreesAreOneStoredTreeAndSixteenInstances) {
    CountingSink sink;
    const GeneratorReport report = run("forest:trees=16,seed=3", sink);
    ASSERT_EQ(sink.prototypes.size(), 1u);
    EXPECT_EQ(sink.instances.size(), 16u);
    EXPECT_GE(report.storedTriangles, 45'000u);
    EXPECT_LE(report.storedTriangles, 55'000u);
    EXPECT_EQ(report.triangles, 16 * report.storedTriangles);
    EXPECT_EQ(sink.zeroAreaTriangles, 0u);
    EXPECT_EQ(sink.nonFiniteTriangles, 0u);
    expectReportMatchesSink(report, sink);
}

TEST(ForestGeneratorTest, TreeTriangleCountDoesNotDependOnTheSeed) {
    CountingSink a;
    CountingSink b;
    EXPECT_EQ(
            run("forest:trees=1,seed=1", a).storedTriangles,
            run("forest:trees=1,seed=99", b).storedTriangles);
}

TEST(ForestGeneratorTest, TreeIsAboutTenUnitsTallAndStandsOnTheOrigin) {
    CountingSink sink;
    run("forest:trees=1", sink);
    const CountingSink::PrototypeStats& tree = sink.prototypes.at(0);
    const float height = tree.boundsMax.y - tree.boundsMin.y;
    EXPECT_GT(height, 7.0f);
    EXPECT_LT(height, 13.0f);
    EXPECT_LT(std::fabs(tree.boundsMin.y), 0.5f); // roots at the ground
    EXPECT_GT(tree.maxRadialXZ, 1.0f);
    EXPECT_LT(tree.maxRadialXZ, 10.0f);
}

TEST(ForestGeneratorTest, InstancesFormARecursive2x2GridWithoutOverlap) {
    CountingSink sink;
    run("forest:trees=16,seed=5", sink);
    ASSERT_EQ(sink.instances.size(), 16u);
    const float radius = sink.prototypes.at(0).maxRadialXZ;

    std::set<float> xs;
    std::set<float> zs;
    std::set<std::pair<float, float>> cells;
    for (const CountingSink::Instance& instance : sink.instances) {
        const glm::vec3 t = translationOf(instance.transform);
        EXPECT_EQ(t.y, 0.0f);
        xs.insert(t.x);
        zs.insert(t.z);
        cells.insert({t.x, t.z});
        const float scale = uniformScaleOf(instance.transform);
        EXPECT_GE(scale, 0.9f - 1e-5f);
        EXPECT_LE(scale, 1.1f + 1e-5f);
        // Rotation about Y only: the Y axis is untouched.
        EXPECT_NEAR(instance.transform[1][1], scale, 1e-5f);
    }
    ASSERT_EQ(xs.size(), 4u);
    ASSERT_EQ(zs.size(), 4u);
    EXPECT_EQ(cells.size(), 16u);
    const std::vector<float> x(xs.begin(), xs.end());
    const float spacing = x[1] - x[0];
    for (std::size_t i = 1; i < x.size(); ++i)
        EXPECT_NEAR(x[i] - x[i - 1], spacing, 1e-3f);
    EXPECT_NEAR(x.front() + x.back(), 0.0f, 1e-3f); // centred

    // No two trees' crowns (scaled bounding cylinders) intersect.
    for (std::size_t i = 0; i < sink.instances.size(); ++i) {
        for (std::size_t j = i + 1; j < sink.instances.size(); ++j) {
            const glm::mat4& a = sink.instances[i].transform;
            const glm::mat4& b = sink.instances[j].transform;
            const float distance = glm::length(translationOf(a) - translationOf(b));
            EXPECT_GT(distance, radius * (uniformScaleOf(a) + uniformScaleOf(b))) << i << "," << j;
        }
    }

    // Recursive layout: each aligned run of 4 instances is a 2x2 block of neighbouring cells.
    for (std::size_t block = 0; block < 4; ++block) {
        std::set<float> bx;
        std::set<float> bz;
        for (std::size_t k = 0; k < 4; ++k) {
            const glm::vec3 t = translationOf(sink.instances[block * 4 + k].transform);
            bx.insert(t.x);
            bz.insert(t.z);
        }
        ASSERT_EQ(bx.size(), 2u);
        ASSERT_EQ(bz.size(), 2u);
        EXPECT_NEAR(*bx.rbegin() - *bx.begin(), spacing, 1e-3f);
        EXPECT_NEAR(*bz.rbegin() - *bz.begin(), spacing, 1e-3f);
    }
}

TEST(ForestGeneratorTest, RefusesTreeCountsThatAreNotPowersOf4) {
    EXPECT_EQ(failureOf("forest:trees=3").code(), ErrorCode::InvalidArgument);
    EXPECT_EQ(failureOf("forest:trees=32").code(), ErrorCode::InvalidArgument);
    EXPECT_TRUE(failureOf("forest:trees=64").isOk());
}

// ---------------------------------------------------------------------------------------------

TEST(TerrainGeneratorTest, ReachesTheRequestedCountWithinARow) {
    CountingSink sink;
    const GeneratorReport report = run("terrain:triangles=100000", sink);
    EXPECT_GE(report.storedTriangles, 100'000u);
    // One row of a ~224-cell-wide grid is ~450 triangles.
    EXPECT_LE(report.storedTriangles, 100'000u + 2 * 450u);
    EXPECT_EQ(report.triangles, report.storedTriangles);
    EXPECT_EQ(report.storedTriangles % 2, 0u);
    expectReportMatchesSink(report, sink);
}

TEST(TerrainGeneratorTest, IsOneIdentityInstance) {
    CountingSink sink;
    run("terrain:triangles=2000", sink);
    ASSERT_EQ(sink.prototypes.size(), 1u);
    ASSERT_EQ(sink.instances.size(), 1u);
    EXPECT_EQ(sink.instances[0].transform, glm::mat4(1.0f));
}

TEST(TerrainGeneratorTest, TrianglesAreFiniteWithAreaAndStreamInBoundedBatches) {
    CountingSink sink;
    const GeneratorReport report = run("terrain:triangles=100000,seed=11", sink);
    EXPECT_EQ(sink.nonFiniteTriangles, 0u);
    EXPECT_EQ(sink.zeroAreaTriangles, 0u);
    // Bounded batches: memory does not grow with the scene, and the calls are amortised.
    EXPECT_LE(sink.maxBatch, 16'384u);
    EXPECT_GE(sink.batches, report.storedTriangles / 16'384u);
    EXPECT_GE(sink.maxBatch, 256u);
}

TEST(TerrainGeneratorTest, ExtentGrowsWithTheSquareRootOfTheCount) {
    CountingSink small;
    CountingSink large;
    run("terrain:triangles=20000", small);
    run("terrain:triangles=80000", large);
    const glm::vec3 smallSize = small.prototypes[0].boundsMax - small.prototypes[0].boundsMin;
    const glm::vec3 largeSize = large.prototypes[0].boundsMax - large.prototypes[0].boundsMin;
    EXPECT_NEAR(largeSize.x / smallSize.x, 2.0f, 0.1f);
    EXPECT_NEAR(largeSize.z / smallSize.z, 2.0f, 0.1f);
    // ~1-unit cells: 10,000 cells is about 100 x 100 units.
    EXPECT_NEAR(smallSize.x, 100.0f, 5.0f);
    // Gentle relief: heights well below the horizontal extent.
    EXPECT_GT(largeSize.y, 0.5f);
    EXPECT_LT(largeSize.y, largeSize.x);
}

TEST(TerrainGeneratorTest, TinyCountsRoundUpToWholeCells) {
    CountingSink one;
    EXPECT_EQ(run("terrain:triangles=1", one).storedTriangles, 2u);
    CountingSink seven;
    EXPECT_EQ(run("terrain:triangles=7", seven).storedTriangles, 8u);
}

// ---------------------------------------------------------------------------------------------

TEST(MoleculeGeneratorTest, HundredSpheresAreHundredInstancesOfAtMostFivePrototypes) {
    CountingSink sink;
    const GeneratorReport report = run("molecule:spheres=100,seed=2", sink);
    EXPECT_EQ(sink.instances.size(), 100u);
    EXPECT_GE(sink.prototypes.size(), 2u);
    EXPECT_LE(sink.prototypes.size(), 5u);
    for (const CountingSink::PrototypeStats& atom : sink.prototypes) {
        EXPECT_EQ(atom.triangles, 800u) << atom.name;
        // A unit sphere (no ring need lie exactly on the equator).
        EXPECT_LE(atom.boundsMax.x, 1.0f + 1e-5f) << atom.name;
        EXPECT_GE(atom.boundsMax.x, 0.99f) << atom.name;
        EXPECT_NEAR(atom.boundsMax.y, 1.0f, 1e-5f) << atom.name; // poles on Y
    }
    EXPECT_EQ(report.triangles, 100u * 800u);
    EXPECT_EQ(sink.zeroAreaTriangles, 0u);
    expectReportMatchesSink(report, sink);
}

TEST(MoleculeGeneratorTest, TrianglesPerSphereIsHonoured) {
    CountingSink sink;
    const GeneratorReport report = run("molecule:spheres=10,triangles_per_sphere=200", sink);
    for (const CountingSink::PrototypeStats& atom : sink.prototypes)
        EXPECT_EQ(atom.triangles, 200u) << atom.name;
    EXPECT_EQ(report.triangles, 10u * 200u);
}

TEST(MoleculeGeneratorTest, AtomsFormACompactBlobOfBondedNeighbours) {
    CountingSink sink;
    run("molecule:spheres=2000,triangles_per_sphere=12", sink);
    glm::vec3 centroid(0.0f);
    for (const auto& atom : sink.instances)
        centroid += translationOf(atom.transform) / 2000.0f;
    float gyration2 = 0.0f;
    for (std::size_t i = 0; i < sink.instances.size(); ++i) {
        const glm::mat4& m = sink.instances[i].transform;
        const float radius = uniformScaleOf(m);
        EXPECT_GE(radius, 1.0f);
        EXPECT_LE(radius, 2.0f);
        const glm::vec3 d = translationOf(m) - centroid;
        gyration2 += glm::dot(d, d) / 2000.0f;
        if (i > 0) { // bonded: consecutive atoms overlap but are not concentric
            const glm::mat4& prev = sink.instances[i - 1].transform;
            const float bond = glm::length(translationOf(m) - translationOf(prev));
            EXPECT_GT(bond, 0.3f * (radius + uniformScaleOf(prev)));
            EXPECT_LT(bond, radius + uniformScaleOf(prev));
        }
    }
    // A free random walk of 2000 ~1.9-unit steps has R_g ~ 35; a packed globule ~ 10-20.
    EXPECT_LT(std::sqrt(gyration2), 25.0f);
    EXPECT_GT(std::sqrt(gyration2), 5.0f);
}

// ---------------------------------------------------------------------------------------------

TEST(BlindsGeneratorTest, FiftySlabsAreSixHundredTrianglesInOnePrototype) {
    CountingSink sink;
    const GeneratorReport report = run("blinds:slabs=50", sink);
    EXPECT_EQ(report.storedTriangles, 50u * 12u);
    EXPECT_EQ(report.triangles, 50u * 12u);
    ASSERT_EQ(sink.instances.size(), 1u);
    EXPECT_EQ(sink.instances[0].transform, glm::mat4(1.0f));
    EXPECT_EQ(sink.zeroAreaTriangles, 0u);
    expectReportMatchesSink(report, sink);
}

TEST(BlindsGeneratorTest, SlabsAreParallelWithTheRequestedSpacingAndThickness) {
    CountingSink sink(/*keepTriangles=*/true);
    run("blinds:slabs=50,spacing=0.25,thickness=0.05,width=8,depth=2", sink);
    ASSERT_EQ(sink.triangles.size(), 600u);
    // Horizontal faces: all three corners at one height. Collect those heights.
    std::set<float> heights;
    std::set<std::array<std::uint8_t, 4>> colors;
    for (const storage::PackedTriangle& t : sink.triangles) {
        const float y = t.vertices[0].position[1];
        colors.insert(t.vertices[0].color);
        if (t.vertices[1].position[1] == y && t.vertices[2].position[1] == y)
            heights.insert(y);
    }
    ASSERT_EQ(heights.size(), 100u); // top and bottom of each slab
    const std::vector<float> h(heights.begin(), heights.end());
    for (std::size_t k = 0; k + 1 < h.size(); k += 2) {
        EXPECT_NEAR(h[k + 1] - h[k], 0.05f, 1e-4f); // thickness
        if (k + 2 < h.size()) {
            EXPECT_NEAR(h[k + 2] - h[k], 0.25f, 1e-4f); // spacing
        }
    }
    EXPECT_EQ(colors.size(), 2u); // alternating colours
    const glm::vec3 size = sink.prototypes[0].boundsMax - sink.prototypes[0].boundsMin;
    EXPECT_NEAR(size.x, 8.0f, 1e-4f);
    EXPECT_NEAR(size.z, 2.0f, 1e-4f);
}

TEST(SphereGeneratorTest, TriangleCountFollowsTheLatitudeLongitudeGrid) {
    CountingSink sink;
    // 10000 triangles: 50 rings of 100 segments, caps of one triangle per segment.
    const GeneratorReport report = run("sphere:triangles=10000", sink);
    EXPECT_EQ(report.storedTriangles, 2u * 100u * 49u);
    ASSERT_EQ(sink.instances.size(), 1u);
    EXPECT_EQ(sink.instances[0].transform, glm::mat4(1.0f));
    EXPECT_EQ(sink.zeroAreaTriangles, 0u);
    expectReportMatchesSink(report, sink);
}

TEST(SphereGeneratorTest, IsAClosedOutwardFacingSurfaceWithRadialNormals) {
    CountingSink sink(/*keepTriangles=*/true);
    run("sphere:triangles=4000,radius=5", sink);
    ASSERT_FALSE(sink.triangles.empty());
    for (const storage::PackedTriangle& t : sink.triangles) {
        glm::vec3 corner[3];
        for (int i = 0; i < 3; ++i) {
            const auto& v = t.vertices[static_cast<std::size_t>(i)];
            corner[i] = glm::vec3(v.position[0], v.position[1], v.position[2]);
            ASSERT_NEAR(glm::length(corner[i]), 5.0f, 1e-4f);
        }
        const glm::vec3 faceNormal = glm::cross(corner[1] - corner[0], corner[2] - corner[0]);
        const glm::vec3 centroid = (corner[0] + corner[1] + corner[2]) / 3.0f;
        ASSERT_GT(glm::dot(faceNormal, centroid), 0.0f) << "a triangle faces inwards";
    }
    const glm::vec3 size = sink.prototypes[0].boundsMax - sink.prototypes[0].boundsMin;
    EXPECT_NEAR(size.x, 10.0f, 1e-3f);
    EXPECT_NEAR(size.y, 10.0f, 1e-3f);
    EXPECT_NEAR(size.z, 10.0f, 1e-3f);
}


// ---------------------------------------------------------------------------------------------

TEST(CityGeneratorTest, TheDefaultCityIsAtLeastMeissnersSizeMostlyInside) {
    CountingSink sink;
    const GeneratorReport report = run("city", sink);
    EXPECT_GE(report.triangles, 1'400'000u) << "Meißner et al.'s City: >= 1.4 M triangles";
    expectReportMatchesSink(report, sink);
    EXPECT_EQ(sink.zeroAreaTriangles, 0u);
    EXPECT_EQ(sink.nonFiniteTriangles, 0u);
    // Interiors hold most triangles: furniture prototypes are named so.
    std::uint64_t furniture = 0;
    for (const CountingSink::Instance& instance : sink.instances)
        if (sink.prototypes[instance.prototype].name == "furniture")
            furniture += sink.prototypes[instance.prototype].triangles;
    EXPECT_GT(furniture, report.triangles * 8 / 10);
    // Every piece is worth an occlusion test of its own (OcclusionOptions::minTestTriangles).
    for (const CountingSink::PrototypeStats& prototype : sink.prototypes) {
        if (prototype.name == "furniture") {
            EXPECT_GE(prototype.triangles, 256u);
        }
    }
}

TEST(CityGeneratorTest, FlatAndInstancedHoldTheSameTriangles) {
    CountingSink instanced;
    CountingSink flat;
    const GeneratorReport a = run("city:blocks=4,seed=3", instanced);
    const GeneratorReport b = run("city:blocks=4,seed=3,instanced=0", flat);
    EXPECT_EQ(a.triangles, b.triangles);
    EXPECT_EQ(flat.prototypes.size(), 1u);
    EXPECT_EQ(flat.instances.size(), 1u);
    EXPECT_GT(instanced.instances.size(), 16u);
    // The flat city spans the grid: 4 blocks of 20 units, buildings 12 wide on a ground plane.
    const CountingSink::PrototypeStats& city = flat.prototypes[0];
    EXPECT_NEAR(city.boundsMax.x - city.boundsMin.x, 80.0f, 1e-3f);
    EXPECT_NEAR(city.boundsMin.y, -0.2f, 1e-4f);
    EXPECT_LE(city.boundsMax.y, 4 * 3.0f + 1e-3f);
}

TEST(CathedralGeneratorTest, TheDefaultCathedralIsAtLeastMeissnersSize) {
    CountingSink sink;
    const GeneratorReport report = run("cathedral", sink);
    EXPECT_GE(report.triangles, 417'000u) << "Meißner et al.'s Cathedral: 417 k triangles";
    expectReportMatchesSink(report, sink);
    EXPECT_EQ(sink.zeroAreaTriangles, 0u);
    EXPECT_EQ(sink.nonFiniteTriangles, 0u);
    ASSERT_EQ(sink.prototypes.size(), 1u);
    // The nave runs along +z from the west door; the vault tops out at 16 + 7 units.
    const CountingSink::PrototypeStats& church = sink.prototypes[0];
    EXPECT_NEAR(church.boundsMin.z, 0.0f, 1e-4f);
    EXPECT_NEAR(church.boundsMax.z, 6.4f * 13.0f, 1e-3f);
    EXPECT_NEAR(church.boundsMax.y, 23.0f, 1e-3f);
    EXPECT_NEAR(church.boundsMax.x - church.boundsMin.x, 26.0f, 1e-3f);
}

TEST(CathedralGeneratorTest, DetailAndBaysScaleTheTriangles) {
    CountingSink base, detailed, longer;
    const GeneratorReport a = run("cathedral:bays=4", base);
    const GeneratorReport b = run("cathedral:bays=4,detail=2", detailed);
    const GeneratorReport c = run("cathedral:bays=8", longer);
    EXPECT_GT(b.triangles, 3 * a.triangles); // most surfaces tessellate in two directions
    EXPECT_GT(c.triangles, a.triangles + a.triangles / 2);
}

TEST(IsosurfaceGeneratorTest, TheDefaultVolumeIsAtLeastTheVentriclesSize) {
    CountingSink sink;
    const GeneratorReport report = run("isosurface", sink);
    EXPECT_GE(report.triangles, 270'000u) << "Meißner et al.'s ventricular system: 270 k triangles";
    expectReportMatchesSink(report, sink);
    EXPECT_EQ(sink.nonFiniteTriangles, 0u);
    ASSERT_EQ(sink.prototypes.size(), 1u);
    EXPECT_EQ(sink.instances.size(), 1u);
}

/** A generated volume, kept whole: its triangles and the grid it declared. */
testing::RecordingSink recordIsosurface(const std::string& text) {
    testing::RecordingSink sink;
    Result<GeneratorReport> report = runGenerator(specOf(text), sink);
    EXPECT_TRUE(report.isOk()) << report.status().toString();
    return sink;
}

glm::vec3 positionOf(const storage::PackedVertex& v) { return {v.position[0], v.position[1], v.position[2]}; }

TEST(IsosurfaceGeneratorTest, EveryTriangleLiesInOneCellOfTheDeclaredGrid) {
    const testing::RecordingSink sink = recordIsosurface("isosurface:resolution=40");
    ASSERT_EQ(sink.voxelGrids().size(), 1u);
    const VoxelGrid& grid = sink.voxelGrids()[0].second;
    EXPECT_EQ(grid.cells, glm::uvec3(40u));
    const auto& triangles = sink.prototypes()[0].triangles;
    ASSERT_GT(triangles.size(), 1000u);
    for (const storage::PackedTriangle& t : triangles) {
        const glm::vec3 centroid =
                (positionOf(t.vertices[0]) + positionOf(t.vertices[1]) + positionOf(t.vertices[2])) / 3.0f;
        const glm::vec3 cellMin = grid.origin + glm::floor((centroid - grid.origin) / grid.cellSize) * grid.cellSize;
        const float slack = 1e-4f * grid.cellSize;
        for (const storage::PackedVertex& v : t.vertices) {
            const glm::vec3 p = positionOf(v);
            ASSERT_TRUE(glm::all(glm::greaterThanEqual(p, cellMin - slack)) &&
                        glm::all(glm::lessThanEqual(p, cellMin + grid.cellSize + slack)))
                    << "a triangle leaves its grid cell";
        }
    }
}

TEST(IsosurfaceGeneratorTest, TheSurfaceIsClosedAndFacesOutward) {
    const testing::RecordingSink sink = recordIsosurface("isosurface:resolution=48");
    const auto& triangles = sink.prototypes()[0].triangles;
    // Closed and consistently wound: every directed edge appears once, and its reverse once.
    using Point = std::array<float, 3>;
    std::map<std::pair<Point, Point>, int> edges;
    std::size_t degenerate = 0;
    double totalArea = 0.0;
    double inwardArea = 0.0;
    for (const storage::PackedTriangle& t : triangles) {
        const std::array<Point, 3> p = {t.vertices[0].position, t.vertices[1].position, t.vertices[2].position};
        if (p[0] == p[1] || p[1] == p[2] || p[2] == p[0]) {
            ++degenerate; // zero area: dropped by the builder, and they close nothing
            continue;
        }
        for (int e = 0; e < 3; ++e)
            ++edges[{p[static_cast<std::size_t>(e)], p[static_cast<std::size_t>((e + 1) % 3)]}];
        // The face normal agrees with the field's gradient (the shading normal): slivers may
        // tilt past it, so this is by area.
        const glm::vec3 a = positionOf(t.vertices[0]);
        const glm::vec3 face = glm::cross(positionOf(t.vertices[1]) - a, positionOf(t.vertices[2]) - a);
        const std::array<float, 3> n = storage::decodeOctNormal(t.vertices[0].normalOct);
        const float area = glm::length(face);
        totalArea += area;
        inwardArea += glm::dot(face, glm::vec3(n[0], n[1], n[2])) > 0.0f ? 0.0 : area;
    }
    EXPECT_LT(inwardArea, 0.001 * totalArea) << "triangles facing inward";
    EXPECT_LT(degenerate, triangles.size() / 100);
    std::size_t open = 0;
    for (const auto& [edge, count] : edges) {
        const auto reverse = edges.find({edge.second, edge.first});
        open += (count != 1 || reverse == edges.end() || reverse->second != 1) ? 1u : 0u;
    }
    EXPECT_EQ(open, 0u) << "edges not shared by exactly two triangles wound opposite ways";
}

TEST(IsosurfaceGeneratorTest, ResolutionScalesTheTrianglesAndSeedMovesTheBranches) {
    CountingSink coarse, fine, reseeded;
    const GeneratorReport a = run("isosurface:resolution=32", coarse);
    const GeneratorReport b = run("isosurface:resolution=64", fine);
    run("isosurface:resolution=32,seed=2", reseeded);
    EXPECT_GT(b.triangles, 3 * a.triangles); // a surface: four times the cells it crosses
    EXPECT_NE(coarse.triangleHash, reseeded.triangleHash);
}

} // namespace
} // namespace ff::builder
