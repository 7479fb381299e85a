#include "BuiltScene.h"

#include <ff/builder/Generators.h>
#include <ff/storage/SceneFile.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <numeric>
#include <optional>
#include <set>
#include <span>
#include <utility>

namespace ff::builder::testing {

namespace fs = std::filesystem;

// ---- files -----------------------------------------------------------------------------------

fs::path freshTestDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = std::string(info->test_suite_name()) + "." + info->name();
    std::replace(name.begin(), name.end(), '/', '_');
    const fs::path dir = fs::path(FF_TEST_TMP_DIR) / name;
    std::error_code ec;
    fs::remove_all(dir, ec);
    fs::create_directories(dir);
    return dir;
}

// ---- scenes ----------------------------------------------------------------------------------

BuildOptions smallOptions(unsigned threads) {
    BuildOptions options;
    options.memoryBudgetBytes = SceneBuilder::kMinimumBudgetBytes;
    options.pageSize = storage::kMinPageSize; // many pages: node levels and runs cross page ends
    // Format 1: readScene() and expectSceneMatches() walk its records and segments. Until they
    // are ported to format 2 (issue 16: version 1 is to be refused).
    options.formatVersion = storage::kFormatVersion;
    options.threads = threads;
    return options;
}

RecordingSink generate(const std::string& text) {
    RecordingSink scene;
    Result<GeneratorSpec> spec = parseGeneratorSpec(text);
    EXPECT_TRUE(spec.isOk()) << spec.status().toString();
    if (spec.isOk()) {
        Result<GeneratorReport> report = runGenerator(*spec, scene);
        EXPECT_TRUE(report.isOk()) << report.status().toString();
    }
    return scene;
}

Status replay(const RecordingSink& scene, ISceneSink& sink) {
    constexpr std::size_t kBatch = 4096;
    std::vector<PrototypeId> ids;
    for (const RecordingSink::Prototype& p : scene.prototypes()) {
        FF_ASSIGN_OR_RETURN(PrototypeId id, sink.addPrototype(p.name));
        ids.push_back(id);
    }
    for (std::size_t p = 0; p < scene.prototypes().size(); ++p) {
        const auto& triangles = scene.prototypes()[p].triangles;
        for (std::size_t begin = 0; begin < triangles.size(); begin += kBatch) {
            const std::size_t count = std::min(kBatch, triangles.size() - begin);
            FF_RETURN_IF_ERROR(
                    sink.addTriangles(ids[p], std::span(triangles).subspan(begin, count)));
        }
    }
    for (const auto& [prototype, grid] : scene.voxelGrids())
        FF_RETURN_IF_ERROR(sink.declareVoxelGrid(ids[prototype], grid));
    for (const RecordingSink::Instance& instance : scene.instances())
        FF_RETURN_IF_ERROR(sink.addInstance(ids[instance.prototype], instance.transform));
    return Status::ok();
}

Result<BuildReport>
buildScene(const RecordingSink& scene, const fs::path& output, const BuildOptions& options) {
    FF_ASSIGN_OR_RETURN(
            std::unique_ptr<SceneBuilder> builder, SceneBuilder::create(output, options));
    FF_RETURN_IF_ERROR(replay(scene, *builder));
    return builder->finish();
}

BuildReport
buildOrFail(const RecordingSink& scene, const fs::path& output, const BuildOptions& options) {
    Result<BuildReport> report = buildScene(scene, output, options);
    EXPECT_TRUE(report.isOk()) << report.status().toString();
    return report.isOk() ? report.value() : BuildReport{};
}

SourceVertex vertexAt(const glm::vec3& p, const glm::vec3& color) {
    return {p, glm::vec3(0.0f), glm::vec4(color, 1.0f)};
}

storage::PackedTriangle triangleAt(const glm::vec3& c, float size) {
    const float t = size / 3.0f;
    return packTriangle(
            vertexAt(c + glm::vec3(-t, -t, 0.5f * t)),
            vertexAt(c + glm::vec3(2.0f * t, -t, -t)),
            vertexAt(c + glm::vec3(-t, 2.0f * t, 0.5f * t)));
}

std::vector<storage::PackedTriangle>
cluster(std::size_t count, const glm::vec3& lo, const glm::vec3& hi, std::uint64_t seed) {
    Lcg rng(seed);
    std::vector<storage::PackedTriangle> out;
    out.reserve(count);
    for (std::size_t i = 0; i < count; ++i)
        out.push_back(triangleAt(rng.inBox(lo, hi), 0.002f));
    return out;
}

RecordingSink singlePrototypeScene(const std::vector<storage::PackedTriangle>& triangles) {
    RecordingSink scene;
    const PrototypeId id = scene.addPrototype("mesh").value();
    EXPECT_TRUE(scene.addTriangles(id, triangles).isOk());
    EXPECT_TRUE(scene.addInstance(id, glm::mat4(1.0f)).isOk());
    return scene;
}

namespace {

bool isDrawable(const storage::PackedTriangle& t) {
    std::array<glm::dvec3, 3> p;
    for (std::size_t k = 0; k < 3; ++k) {
        for (int a = 0; a < 3; ++a) {
            if (!std::isfinite(t.vertices[k].position[static_cast<std::size_t>(a)]))
                return false;
            p[k][a] = t.vertices[k].position[static_cast<std::size_t>(a)];
        }
    }
    const glm::dvec3 n = glm::cross(p[1] - p[0], p[2] - p[0]);
    return glm::dot(n, n) > 0.0;
}

std::string bytesOf(const storage::PackedTriangle& t) {
    return {reinterpret_cast<const char*>(&t), sizeof(t)}; // byte view: may alias
}

/** The drawable triangles of each prototype as sorted byte strings (a multiset). */
std::vector<std::vector<std::string>> expectedTriangles(const RecordingSink& scene) {
    std::vector<std::vector<std::string>> out;
    for (const RecordingSink::Prototype& p : scene.prototypes()) {
        std::vector<std::string> bytes;
        for (const storage::PackedTriangle& t : p.triangles)
            if (isDrawable(t))
                bytes.push_back(bytesOf(t));
        std::sort(bytes.begin(), bytes.end());
        out.push_back(std::move(bytes));
    }
    return out;
}

// ---- reading a scene back --------------------------------------------------------------------

bool contains(
        const std::array<float, 3>& lo,
        const std::array<float, 3>& hi,
        const std::array<float, 3>& p) {
    for (std::size_t a = 0; a < 3; ++a)
        if (!(lo[a] <= p[a] && p[a] <= hi[a]))
            return false;
    return true;
}

/**
 * Walks one hierarchy depth-first: every node record valid, reached once, its bounds inside its
 * parent's, its children inside one page, its own triangles inside its bounds. Cell triangles
 * go to `triangles`, Instance nodes to `instanceNodes`.
 */
void walkHierarchy(
        const storage::SceneFile& file,
        storage::NodeRef root,
        std::set<std::pair<std::uint32_t, std::uint32_t>>& seen,
        std::uint64_t& nodes,
        std::vector<std::string>& triangles,
        std::vector<std::uint32_t>& instanceNodes) {
    struct Item {
        storage::NodeRef ref;
        std::optional<storage::NodeRecord> parent;
    };
    const std::uint32_t slots = storage::nodesPerPage(file.pageSize());
    std::vector<Item> stack = {{root, std::nullopt}};
    std::vector<storage::GeometrySegment> segments;
    while (!stack.empty()) {
        const Item item = stack.back();
        stack.pop_back();
        ASSERT_TRUE(seen.insert({item.ref.page, item.ref.slot}).second)
                << "node (" << item.ref.page << ", " << item.ref.slot << ") reached twice";
        Result<storage::NodeRecord> record = file.node(item.ref);
        ASSERT_TRUE(record.isOk()) << record.status().toString();
        const storage::NodeRecord& node = *record;
        ++nodes;
        if (item.parent) {
            EXPECT_TRUE(
                    contains(item.parent->boundsMin, item.parent->boundsMax, node.boundsMin) &&
                    contains(item.parent->boundsMin, item.parent->boundsMax, node.boundsMax))
                    << "node (" << item.ref.page << ", " << item.ref.slot
                    << ") pokes out of its parent";
        }
        EXPECT_NE(node.flags & storage::kNodeHasCube, 0);
        if (node.kind == static_cast<std::uint8_t>(storage::NodeKind::Instance)) {
            EXPECT_EQ(node.childCount, 0);
            instanceNodes.push_back(node.geometryPage);
            continue;
        }
        segments.clear();
        ASSERT_TRUE(file.geometrySegments(node, segments).isOk());
        std::uint64_t own = 0;
        for (const storage::GeometrySegment& segment : segments) {
            Result<std::span<const std::byte>> bytes = file.segmentBytes(segment);
            ASSERT_TRUE(bytes.isOk()) << bytes.status().toString();
            for (std::size_t i = 0; i < segment.count; ++i) {
                storage::PackedTriangle t;
                std::memcpy(&t, bytes->data() + i * sizeof(t), sizeof(t));
                for (const storage::PackedVertex& v : t.vertices)
                    EXPECT_TRUE(contains(node.boundsMin, node.boundsMax, v.position))
                            << "triangle outside its node's bounds";
                triangles.push_back(bytesOf(t));
                ++own;
            }
        }
        EXPECT_EQ(own, node.geometryCount);
        if (node.childCount > 0) {
            // The reader already refuses child lists that cross a page end; say it here too.
            EXPECT_LE(node.firstChild.slot + node.childCount, slots);
        }
        for (std::uint32_t c = node.childCount; c-- > 0;)
            stack.push_back({storage::SceneFile::childRef(node, c), node});
    }
}

} // namespace

void readScene(const fs::path& path, StoredScene& out) {
    Result<std::unique_ptr<storage::SceneFile>> file = storage::SceneFile::open(path);
    ASSERT_TRUE(file.isOk()) << file.status().toString();
    out.file = std::move(file.value());
    const storage::SceneFile& f = *out.file;
    ASSERT_TRUE(f.verifyAll().isOk()) << f.verifyAll().toString();

    std::set<std::pair<std::uint32_t, std::uint32_t>> seen;
    std::vector<std::string> noTriangles;
    ASSERT_NE(f.header().root, storage::kNullNodeRef);
    ASSERT_NO_FATAL_FAILURE(
            walkHierarchy(f, f.header().root, seen, out.nodes, noTriangles, out.instanceNodes));
    EXPECT_TRUE(noTriangles.empty()) << "the instance level holds no geometry of its own";

    for (const storage::PrototypeRecord& prototype : f.prototypes()) {
        std::vector<std::string> triangles;
        std::vector<std::uint32_t> instances;
        std::uint64_t nodes = 0;
        ASSERT_NO_FATAL_FAILURE(
                walkHierarchy(f, prototype.root, seen, nodes, triangles, instances));
        EXPECT_TRUE(instances.empty()) << "a prototype holds no instances";
        EXPECT_EQ(prototype.triangleCount, triangles.size());
        EXPECT_EQ(prototype.nodeCount, nodes);
        std::sort(triangles.begin(), triangles.end());
        out.storedTriangles += triangles.size();
        out.nodes += nodes;
        out.prototypeNodes.push_back(nodes);
        out.prototypeTriangles.push_back(std::move(triangles));
    }
}

void expectSceneMatches(
        const fs::path& path, const RecordingSink& scene, const BuildReport& report) {
    StoredScene stored;
    ASSERT_NO_FATAL_FAILURE(readScene(path, stored));
    const storage::SceneFile& f = *stored.file;

    // Every drawable triangle exactly once, in the prototype it was given to.
    const std::vector<std::vector<std::string>> expected = expectedTriangles(scene);
    std::vector<std::size_t> nonEmpty;
    for (std::size_t p = 0; p < expected.size(); ++p)
        if (!expected[p].empty())
            nonEmpty.push_back(p);
    ASSERT_EQ(stored.prototypeTriangles.size(), nonEmpty.size());
    for (std::size_t i = 0; i < nonEmpty.size(); ++i)
        EXPECT_TRUE(stored.prototypeTriangles[i] == expected[nonEmpty[i]])
                << "prototype " << nonEmpty[i] << " differs";

    // Counts.
    EXPECT_EQ(f.header().storedTriangles, stored.storedTriangles);
    EXPECT_EQ(f.header().nodeCount, stored.nodes);
    EXPECT_EQ(report.storedTriangles, stored.storedTriangles);
    EXPECT_EQ(report.nodes, stored.nodes);
    std::uint64_t instanced = 0;
    for (const storage::InstanceRecord& instance : f.instances())
        instanced += f.prototypes()[instance.prototype].triangleCount;
    EXPECT_EQ(f.header().instancedTriangles, instanced);
    EXPECT_EQ(report.instancedTriangles, instanced);
    EXPECT_EQ(report.instances, f.instances().size());

    // Each instance is reached through exactly one Instance node.
    std::vector<std::uint32_t> indices = stored.instanceNodes;
    std::sort(indices.begin(), indices.end());
    std::vector<std::uint32_t> all(f.instances().size());
    std::iota(all.begin(), all.end(), 0u);
    EXPECT_EQ(indices, all);
}

} // namespace ff::builder::testing
