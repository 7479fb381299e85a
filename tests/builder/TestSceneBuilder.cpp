// SceneBuilder end to end: scenes go in through ISceneSink, come out as .ffs files, and are read
// back through storage::SceneFile. Every stored triangle must be reachable exactly once from the
// prototype roots, the counts in the header must match what is reachable, the build must be
// deterministic, and no temporary file may outlive a build, whether it succeeds or fails.

#include "BuiltScene.h"
#include "RecordingSink.h"

#include <ff/builder/Generators.h>
#include <ff/builder/SceneBuilder.h>
#include <ff/storage/SceneFile.h>

#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <memory>
#include <numeric>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace ff::builder {
namespace {

namespace fs = std::filesystem;
using namespace testing;

// ---- files ----------------------------------------------------------------------------------

/** Names in `dir`, hidden ones included, sorted. */
std::vector<std::string> listDirectory(const fs::path& dir) {
    std::vector<std::string> names;
    for (const fs::directory_entry& entry : fs::directory_iterator(dir))
        names.push_back(entry.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
}

std::vector<char> readBytes(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// ---- every triangle once ---------------------------------------------------------------------

TEST(SceneBuilderTest, EveryTriangleIsStoredExactlyOnce) {
    const fs::path dir = freshTestDir();
    const RecordingSink scene = generate("terrain:triangles=22000");
    BuildOptions options = smallOptions();
    options.spillCodec = SpillCodec::Raw; // the bytes spilled are then the items spilled
    const BuildReport report = buildOrFail(scene, dir / "terrain.ffs", options);
    EXPECT_EQ(report.inputTriangles, scene.storedTriangles());
    EXPECT_EQ(report.droppedNonFinite + report.droppedDegenerate, 0u);
    EXPECT_EQ(report.storedTriangles, scene.storedTriangles());
    EXPECT_EQ(report.chunks, 1u);
    EXPECT_GT(report.maxDepth, 2u);
    // Built in memory: the prototype's run file is all that was spilled, in blocks of 1 MiB
    // behind 16-byte headers.
    const std::uint64_t runBytes = scene.storedTriangles() * sizeof(storage::PackedTriangle);
    EXPECT_GE(report.spillBytes, runBytes + 16);
    EXPECT_LE(report.spillBytes, runBytes + 16 * (runBytes / (1u << 19) + 1));
    expectSceneMatches(dir / "terrain.ffs", scene, report);
}

TEST(SceneBuilderTest, DefaultPageSizeAndLargeTrianglesRoundTrip) {
    const fs::path dir = freshTestDir();
    std::vector<storage::PackedTriangle> triangles =
            cluster(3000, glm::vec3(0.0f), glm::vec3(1.0f), 1);
    // Large triangles that stay at inner nodes.
    for (int k = 0; k < 20; ++k)
        triangles.push_back(triangleAt(glm::vec3(0.5f, 0.5f, 0.05f * static_cast<float>(k)), 0.6f));
    const RecordingSink scene = singlePrototypeScene(triangles);
    BuildOptions options = smallOptions();
    options.pageSize = storage::kDefaultPageSize;
    const BuildReport report = buildOrFail(scene, dir / "scene.ffs", options);
    expectSceneMatches(dir / "scene.ffs", scene, report);
}

/** Every node of the file in breadth-first order from the root (instances descending into their
 *  prototypes), with where it is stored left out: its record less the page and slot fields, then
 *  its own triangles. Two files with equal signatures hold the same hierarchy. */
std::vector<std::string> hierarchySignature(const storage::SceneFile& file) {
    std::vector<std::string> signature;
    std::vector<storage::NodeRef> queue = {file.header().root};
    std::vector<storage::GeometrySegment> segments;
    for (std::size_t i = 0; i < queue.size(); ++i) {
        Result<storage::NodeRecord> record = file.node(queue[i]);
        EXPECT_TRUE(record.isOk()) << record.status().toString();
        if (!record.isOk())
            return signature;
        storage::NodeRecord node = *record;
        for (std::uint32_t c = 0; c < node.childCount; ++c)
            queue.push_back(storage::SceneFile::childRef(node, c));
        std::string entry;
        if (node.kind == static_cast<std::uint8_t>(storage::NodeKind::Instance)) {
            queue.push_back(file.prototypes()[file.instances()[node.geometryPage].prototype].root);
        } else {
            segments.clear();
            EXPECT_TRUE(file.geometrySegments(node, segments).isOk());
            for (const storage::GeometrySegment& segment : segments) {
                Result<std::span<const std::byte>> bytes = file.segmentBytes(segment);
                EXPECT_TRUE(bytes.isOk());
                if (bytes.isOk())
                    entry.append(reinterpret_cast<const char*>(bytes->data()), bytes->size());
            }
            node.geometryPage = 0;
            node.geometryFirst = 0;
        }
        node.firstChild = storage::kNullNodeRef;
        entry.insert(0, reinterpret_cast<const char*>(&node), sizeof(node));
        signature.push_back(std::move(entry));
    }
    return signature;
}

// `--page-size auto` is the default: a small scene gets small pages, so its file loses most of
// its padding, and nothing else changes: the same nodes, cubes and triangles in the same order.
TEST(SceneBuilderTest, AutoPageSizeShrinksSmallScenesAndKeepsTheirHierarchy) {
    const fs::path dir = freshTestDir();
    const std::vector<std::pair<std::string, RecordingSink>> scenes = {
            {"mesh", singlePrototypeScene(cluster(700, glm::vec3(0.0f), glm::vec3(1.0f), 3))},
            {"molecule", generate("molecule:spheres=16,triangles_per_sphere=300")}};
    for (const auto& [name, scene] : scenes) {
        SCOPED_TRACE(name);
        BuildOptions automatic = smallOptions();
        automatic.pageSize.reset();
        BuildOptions fixed = smallOptions();
        fixed.pageSize = storage::kDefaultPageSize;
        const BuildReport autoReport = buildOrFail(scene, dir / (name + "-auto.ffs"), automatic);
        const BuildReport fixedReport = buildOrFail(scene, dir / (name + "-64k.ffs"), fixed);
        EXPECT_TRUE(autoReport.pageSizeAuto);
        EXPECT_FALSE(fixedReport.pageSizeAuto);
        EXPECT_LT(autoReport.pageSize, storage::kDefaultPageSize);
        expectSceneMatches(dir / (name + "-auto.ffs"), scene, autoReport);
        EXPECT_EQ(autoReport.fileBytes, fs::file_size(dir / (name + "-auto.ffs")));
        EXPECT_LT(autoReport.fileBytes * 2, fixedReport.fileBytes);

        Result<std::unique_ptr<storage::SceneFile>> autoFile = storage::SceneFile::open(dir / (name + "-auto.ffs"));
        Result<std::unique_ptr<storage::SceneFile>> fixedFile = storage::SceneFile::open(dir / (name + "-64k.ffs"));
        ASSERT_TRUE(autoFile.isOk() && fixedFile.isOk());
        EXPECT_EQ((*autoFile)->pageSize(), autoReport.pageSize);
        EXPECT_EQ(hierarchySignature(**autoFile), hierarchySignature(**fixedFile));
    }
}

// A frame refines every node down to its cut, so the builder writes a subtree's node records and
// their triangles in breadth-first order (docs/results/paging.md: the pages a cut needs then
// hold little it does not use). Walking a prototype built in one piece breadth-first must meet
// node slots in increasing file order, and each node's triangles right after the previous
// node's, with and without large triangles kept at inner nodes.
TEST(SceneBuilderTest, NodesAndTrianglesAreWrittenInBreadthFirstOrder) {
    const fs::path dir = freshTestDir();
    std::vector<storage::PackedTriangle> withLarge = cluster(3000, glm::vec3(0.0f), glm::vec3(1.0f), 5);
    for (int k = 0; k < 20; ++k)
        withLarge.push_back(triangleAt(glm::vec3(0.5f, 0.5f, 0.05f * static_cast<float>(k)), 0.6f));
    const std::vector<std::pair<std::string, RecordingSink>> scenes = {
            {"terrain", generate("terrain:triangles=22000")}, {"large", singlePrototypeScene(withLarge)}};
    for (const auto& [name, scene] : scenes) {
        SCOPED_TRACE(name);
        const fs::path file = dir / (name + ".ffs");
        const BuildReport report = buildOrFail(scene, file, smallOptions());
        ASSERT_EQ(report.chunks, 1u); // one subtree, one breadth-first order
        Result<std::unique_ptr<storage::SceneFile>> opened = storage::SceneFile::open(file);
        ASSERT_TRUE(opened.isOk()) << opened.status().toString();
        const storage::SceneFile& sceneFile = **opened;
        const std::uint32_t perPage = storage::trianglesPerPage(sceneFile.pageSize());
        ASSERT_EQ(sceneFile.prototypes().size(), 1u);

        std::vector<storage::NodeRef> queue = {sceneFile.prototypes()[0].root};
        std::uint64_t nextTriangle = 0; // page * perPage + slot of the next run
        bool firstRun = true;
        std::uint64_t triangles = 0;
        for (std::size_t i = 0; i < queue.size(); ++i) {
            if (i > 0) {
                const auto before = std::pair(queue[i - 1].page, queue[i - 1].slot);
                ASSERT_LT(before, std::pair(queue[i].page, queue[i].slot)) << "node " << i;
            }
            Result<storage::NodeRecord> node = sceneFile.node(queue[i]);
            ASSERT_TRUE(node.isOk()) << node.status().toString();
            for (std::uint32_t c = 0; c < node->childCount; ++c)
                queue.push_back(storage::SceneFile::childRef(*node, c));
            if (node->geometryCount == 0)
                continue;
            const std::uint64_t start = std::uint64_t{node->geometryPage} * perPage + node->geometryFirst;
            if (!firstRun) {
                EXPECT_EQ(start, nextTriangle) << "node " << i;
            }
            firstRun = false;
            // A run continues at slot 0 of the next page (FORMAT.md section 6).
            nextTriangle = start + node->geometryCount;
            triangles += node->geometryCount;
        }
        EXPECT_EQ(queue.size(), sceneFile.prototypes()[0].nodeCount);
        EXPECT_EQ(triangles, scene.storedTriangles());
    }
}

// ---- instancing ------------------------------------------------------------------------------

TEST(SceneBuilderTest, InstancedPrototypeIsStoredOnce) {
    const fs::path dir = freshTestDir();
    RecordingSink scene;
    const PrototypeId id = scene.addPrototype("rock").value();
    const std::vector<storage::PackedTriangle> rock =
            cluster(500, glm::vec3(-1.0f), glm::vec3(1.0f), 9);
    ASSERT_TRUE(scene.addTriangles(id, rock).isOk());
    constexpr int kInstances = 40;
    std::vector<glm::mat4> transforms;
    for (int i = 0; i < kInstances; ++i) {
        glm::mat4 m = glm::translate(
                glm::mat4(1.0f),
                glm::vec3(
                        4.0f * static_cast<float>(i % 8), 0.0f, 4.0f * static_cast<float>(i / 8)));
        m = glm::rotate(m, 0.3f * static_cast<float>(i), glm::vec3(0.0f, 1.0f, 0.0f));
        m = glm::scale(m, glm::vec3(0.5f + 0.05f * static_cast<float>(i)));
        transforms.push_back(m);
        ASSERT_TRUE(scene.addInstance(id, m).isOk());
    }
    // Two instances in the same place: space cannot separate them.
    ASSERT_TRUE(scene.addInstance(id, transforms[3]).isOk());
    transforms.push_back(transforms[3]);

    const BuildReport report = buildOrFail(scene, dir / "rocks.ffs", smallOptions());
    EXPECT_EQ(report.storedTriangles, rock.size());
    EXPECT_EQ(report.instancedTriangles, rock.size() * transforms.size());
    EXPECT_EQ(report.instances, transforms.size());
    expectSceneMatches(dir / "rocks.ffs", scene, report);

    Result<std::unique_ptr<storage::SceneFile>> file = storage::SceneFile::open(dir / "rocks.ffs");
    ASSERT_TRUE(file.isOk());
    const storage::SceneFile& f = **file;
    EXPECT_EQ(f.header().storedTriangles, rock.size());
    ASSERT_EQ(f.prototypes().size(), 1u);
    ASSERT_EQ(f.instances().size(), transforms.size());
    for (std::size_t i = 0; i < transforms.size(); ++i) {
        EXPECT_EQ(f.instances()[i].prototype, 0u);
        for (int row = 0; row < 3; ++row)
            for (int col = 0; col < 4; ++col)
                EXPECT_EQ(
                        f.instances()[i].transform[static_cast<std::size_t>(row * 4 + col)],
                        transforms[i][col][row]);
    }
}

TEST(SceneBuilderTest, ManyPrototypesAndInstancesFromAGenerator) {
    const fs::path dir = freshTestDir();
    const RecordingSink scene = generate("molecule:spheres=200");
    ASSERT_GT(scene.prototypes().size(), 1u);
    const BuildReport report = buildOrFail(scene, dir / "molecule.ffs", smallOptions());
    EXPECT_EQ(report.prototypes, scene.prototypes().size());
    EXPECT_EQ(report.instances, scene.instances().size());
    expectSceneMatches(dir / "molecule.ffs", scene, report);
}

// ---- invalid input ---------------------------------------------------------------------------

TEST(SceneBuilderTest, DropsNonFiniteAndZeroAreaTrianglesAndCountsThem) {
    const fs::path dir = freshTestDir();
    std::vector<storage::PackedTriangle> triangles =
            cluster(100, glm::vec3(0.0f), glm::vec3(1.0f), 4);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();
    auto broken = [&](std::size_t base, int vertex, int axis, float value) {
        storage::PackedTriangle t = triangles[base];
        t.vertices[static_cast<std::size_t>(vertex)].position[static_cast<std::size_t>(axis)] =
                value;
        return t;
    };
    std::vector<storage::PackedTriangle> input;
    for (std::size_t i = 0; i < triangles.size(); ++i) {
        input.push_back(triangles[i]);
        if (i == 10)
            input.push_back(broken(i, 0, 0, nan));
        if (i == 20)
            input.push_back(broken(i, 2, 1, inf));
        if (i == 30)
            input.push_back(broken(i, 1, 2, -inf));
        if (i == 40) // all three vertices equal
            input.push_back(packTriangle(
                    vertexAt(glm::vec3(0.5f)),
                    vertexAt(glm::vec3(0.5f)),
                    vertexAt(glm::vec3(0.5f))));
        if (i == 50) // collinear
            input.push_back(packTriangle(
                    vertexAt(glm::vec3(0.1f)),
                    vertexAt(glm::vec3(0.2f)),
                    vertexAt(glm::vec3(0.4f))));
    }
    input.push_back(broken(0, 1, 1, nan)); // last in its batch
    const RecordingSink scene = singlePrototypeScene(input);
    const BuildReport report = buildOrFail(scene, dir / "scene.ffs", smallOptions());
    EXPECT_EQ(report.inputTriangles, input.size());
    EXPECT_EQ(report.droppedNonFinite, 4u);
    EXPECT_EQ(report.droppedDegenerate, 2u);
    EXPECT_EQ(report.storedTriangles, 100u);
    expectSceneMatches(dir / "scene.ffs", scene, report);
}

TEST(SceneBuilderTest, RefusesInstanceWithNonFiniteTransform) {
    const fs::path dir = freshTestDir();
    Result<std::unique_ptr<SceneBuilder>> builder =
            SceneBuilder::create(dir / "scene.ffs", smallOptions());
    ASSERT_TRUE(builder.isOk()) << builder.status().toString();
    SceneBuilder& b = **builder;
    const PrototypeId id = b.addPrototype("mesh").value();
    const std::vector<storage::PackedTriangle> triangles =
            cluster(50, glm::vec3(0.0f), glm::vec3(1.0f), 2);
    ASSERT_TRUE(b.addTriangles(id, triangles).isOk());
    glm::mat4 bad(1.0f);
    bad[3][1] = std::numeric_limits<float>::quiet_NaN();
    EXPECT_EQ(b.addInstance(id, bad).code(), ErrorCode::InvalidInput);
    bad = glm::mat4(1.0f);
    bad[0][0] = std::numeric_limits<float>::infinity();
    EXPECT_EQ(b.addInstance(id, bad).code(), ErrorCode::InvalidInput);
    ASSERT_TRUE(b.addInstance(id, glm::mat4(1.0f)).isOk());
    EXPECT_EQ(b.addInstance(id + 1, glm::mat4(1.0f)).code(), ErrorCode::InvalidArgument);
    EXPECT_EQ(b.addTriangles(id + 1, triangles).code(), ErrorCode::InvalidArgument);
    Result<BuildReport> report = b.finish();
    ASSERT_TRUE(report.isOk()) << report.status().toString();
    EXPECT_EQ(report->instances, 1u);
    EXPECT_EQ(report->instancedTriangles, 50u);
}

TEST(SceneBuilderTest, PrototypeWithoutDrawableTrianglesIsLeftOut) {
    const fs::path dir = freshTestDir();
    RecordingSink scene;
    const PrototypeId empty = scene.addPrototype("nothing").value();
    const PrototypeId mesh = scene.addPrototype("mesh").value();
    const PrototypeId broken = scene.addPrototype("broken").value();
    ASSERT_TRUE(scene.addTriangles(mesh, cluster(200, glm::vec3(0.0f), glm::vec3(1.0f), 3)).isOk());
    storage::PackedTriangle nanTriangle = cluster(1, glm::vec3(0.0f), glm::vec3(1.0f), 5)[0];
    nanTriangle.vertices[0].position[0] = std::numeric_limits<float>::quiet_NaN();
    ASSERT_TRUE(scene.addTriangles(broken, std::span(&nanTriangle, 1)).isOk());
    for (PrototypeId p : {empty, mesh, broken, mesh})
        ASSERT_TRUE(
                scene.addInstance(
                             p, glm::translate(glm::mat4(1.0f), glm::vec3(static_cast<float>(p))))
                        .isOk());
    const BuildReport report = buildOrFail(scene, dir / "scene.ffs", smallOptions());
    EXPECT_EQ(report.prototypes, 3u);
    EXPECT_EQ(report.emptyPrototypes, 2u);
    EXPECT_EQ(report.instances, 2u);
    EXPECT_EQ(report.instancedTriangles, 400u);
    expectSceneMatches(dir / "scene.ffs", scene, report);
}

// ---- determinism -----------------------------------------------------------------------------

TEST(SceneBuilderTest, SameInputGivesByteIdenticalFiles) {
    const fs::path dir = freshTestDir();
    const RecordingSink scene = generate("molecule:spheres=100");
    for (unsigned threads : {1u, 2u}) {
        SCOPED_TRACE(::testing::Message() << threads << " threads");
        const BuildOptions options = smallOptions(threads);
        buildOrFail(scene, dir / "a.ffs", options);
        buildOrFail(scene, dir / "b.ffs", options);
        const std::vector<char> a = readBytes(dir / "a.ffs");
        ASSERT_FALSE(a.empty());
        EXPECT_TRUE(a == readBytes(dir / "b.ffs"));
    }
}

// A build on one thread and on three: the same bytes (the thread count, which defaults to the
// machine's cores, is not written into the file). Prototypes that fit one chunk here; a chunked
// prototype's chunks are still sized by budget / threads (issue 18).
TEST(SceneBuilderTest, TheThreadCountDoesNotChangeTheFile) {
    const fs::path dir = freshTestDir();
    const RecordingSink scene = generate("molecule:spheres=300");
    const BuildReport one = buildOrFail(scene, dir / "one.ffs", smallOptions(1));
    const BuildReport three = buildOrFail(scene, dir / "three.ffs", smallOptions(3));
    EXPECT_EQ(one.threads, 1u);
    EXPECT_EQ(three.threads, 3u);
    EXPECT_EQ(three.chunks, one.chunks);
    EXPECT_TRUE(readBytes(dir / "one.ffs") == readBytes(dir / "three.ffs"));
}

// ---- out of core -----------------------------------------------------------------------------

/** Triangles per chunk for the minimum budget (SceneBuilder::finish, PrototypeBuilder.h). */
std::uint64_t chunkTriangles(unsigned threads) {
    const std::uint64_t budget = SceneBuilder::kMinimumBudgetBytes;
    return (budget - budget / 4) / threads / 160;
}

TEST(SceneBuilderTest, PrototypeLargerThanAChunkIsBuiltOutOfCore) {
    const fs::path dir = freshTestDir();
    constexpr unsigned kThreads = 4;
    const RecordingSink scene = generate("terrain:triangles=60000");
    ASSERT_GT(scene.storedTriangles(), 2 * chunkTriangles(kThreads));
    BuildOptions raw = smallOptions(kThreads);
    raw.spillCodec = SpillCodec::Raw; // the bytes spilled are then the items spilled
    const BuildReport first = buildOrFail(scene, dir / "a.ffs", raw);
    EXPECT_GT(first.chunks, 1u) << buildReportJson(first);
    // The run file, the chunk files (every triangle not kept above the chunks) and the level
    // files of the records below the chunk roots. Triangles go from the chunks straight to the
    // scene file: spilled a third time, they would cost another file's worth of disk and time.
    const std::uint64_t runBytes = scene.storedTriangles() * sizeof(storage::PackedTriangle);
    EXPECT_GT(first.spillBytes, 2 * runBytes);
    // Plus a 16-byte header per block; the smallest chunk buffers hold 4 KiB.
    const std::uint64_t items = 2 * runBytes + first.nodes * sizeof(storage::NodeRecord);
    EXPECT_LE(first.spillBytes, items + items / 256);
    expectSceneMatches(dir / "a.ffs", scene, first);

    // Chunks built on several threads still land in the same order.
    buildOrFail(scene, dir / "b.ffs", raw);
    EXPECT_TRUE(readBytes(dir / "a.ffs") == readBytes(dir / "b.ffs"));
    EXPECT_EQ(listDirectory(dir), (std::vector<std::string>{"a.ffs", "b.ffs"}));
}

// The compact spill is lossless: the same scene, every hierarchy and table page identical to
// the raw spill's (only the build report in the metadata says how much was spilled), from far
// fewer bytes of spill.
TEST(SceneBuilderTest, CompactSpillBuildsTheSameSceneFromFewerBytes) {
    const fs::path dir = freshTestDir();
    const RecordingSink scene = generate("terrain:triangles=60000");
    BuildOptions options = smallOptions(2);
    options.spillCodec = SpillCodec::Raw;
    const BuildReport raw = buildOrFail(scene, dir / "raw.ffs", options);
    options.spillCodec = SpillCodec::Compact;
    const BuildReport compact = buildOrFail(scene, dir / "compact.ffs", options);
    ASSERT_GT(raw.chunks, 1u); // the run file, the chunk files and the level files all spill
    EXPECT_LT(compact.spillBytes, raw.spillBytes / 2) << compact.spillBytes << " of " << raw.spillBytes;
    EXPECT_EQ(compact.spillCodec, "compact");

    auto a = storage::SceneFile::open(dir / "raw.ffs");
    auto b = storage::SceneFile::open(dir / "compact.ffs");
    ASSERT_TRUE(a.isOk() && b.isOk());
    ASSERT_EQ((*a)->pageCount(), (*b)->pageCount());
    std::uint64_t metadataFirst = 0;
    std::uint64_t metadataEnd = 0;
    for (const storage::SectionEntry& s : (*a)->sections()) {
        if (static_cast<storage::SectionType>(s.type) == storage::SectionType::Metadata) {
            metadataFirst = s.firstPage;
            metadataEnd = s.firstPage + s.pageCount;
        }
    }
    for (std::uint64_t page = 1; page < (*a)->pageCount(); ++page) {
        if (page >= metadataFirst && page < metadataEnd)
            continue;
        auto pa = (*a)->source().pinPage(page);
        auto pb = (*b)->source().pinPage(page);
        ASSERT_TRUE(pa.isOk() && pb.isOk()) << page;
        ASSERT_EQ(std::memcmp(pa->bytes().data(), pb->bytes().data(), pa->bytes().size()), 0) << "page " << page;
    }
    EXPECT_EQ((*a)->header().nodeCount, (*b)->header().nodeCount);
    EXPECT_EQ((*a)->header().storedTriangles, (*b)->header().storedTriangles);
}

// A chunked prototype is most of a large build: its phases report progress, each up to its total.
TEST(SceneBuilderTest, ChunkedPrototypeReportsProgressOfEachPhase) {
    const fs::path dir = freshTestDir();
    constexpr unsigned kThreads = 4;
    const RecordingSink scene = generate("terrain:triangles=60000");
    BuildOptions options = smallOptions(kThreads);
    std::vector<BuildProgress> events;
    options.progress = [&events](const BuildProgress& p) { events.push_back(p); };
    const BuildReport report = buildOrFail(scene, dir / "p.ffs", options);
    ASSERT_GT(report.chunks, 1u);

    for (const std::string phase : {"count", "partition", "chunks", "layout"}) {
        std::vector<BuildProgress> seen;
        std::copy_if(events.begin(), events.end(), std::back_inserter(seen), [&](const BuildProgress& p) {
            return p.phase == phase;
        });
        ASSERT_FALSE(seen.empty()) << phase;
        for (std::size_t i = 0; i < seen.size(); ++i) {
            EXPECT_EQ(seen[i].total, seen.back().total) << phase;
            EXPECT_LE(seen[i].done, seen[i].total) << phase;
            if (i > 0) {
                EXPECT_GT(seen[i].done, seen[i - 1].done) << phase;
            }
        }
        EXPECT_EQ(seen.back().done, seen.back().total) << phase;
    }
    const auto last = [&](const std::string& phase) {
        const auto it = std::find_if(events.rbegin(), events.rend(), [&](const BuildProgress& p) { return p.phase == phase; });
        return it->total;
    };
    EXPECT_EQ(last("count"), scene.storedTriangles());
    EXPECT_EQ(last("partition"), scene.storedTriangles());
    EXPECT_EQ(last("chunks"), report.chunks);
    EXPECT_GT(last("layout"), 0u);
}

/** A node as a breadth-first walk meets it. */
struct WalkedNode {
    storage::NodeRef ref;
    storage::NodeRecord record;
};

/** Walks the hierarchy under `root` breadth-first: levels[d] holds depth d's nodes, in order. */
void walkLevels(const storage::SceneFile& file, storage::NodeRef root, std::vector<std::vector<WalkedNode>>& levels) {
    std::vector<storage::NodeRef> level = {root};
    while (!level.empty()) {
        std::vector<storage::NodeRef> next;
        levels.emplace_back();
        for (const storage::NodeRef ref : level) {
            Result<storage::NodeRecord> node = file.node(ref);
            ASSERT_TRUE(node.isOk()) << node.status().toString();
            levels.back().push_back({ref, *node});
            for (std::uint32_t c = 0; c < node->childCount; ++c)
                next.push_back(storage::SceneFile::childRef(*node, c));
        }
        level = std::move(next);
    }
}

// Written each on its own, every chunk a coarse cut enters would cost fresh pages, however few
// of its records the cut needs: a cost that grows with the number of chunks, that is with the
// scene (docs/results/paging.md). The builder writes each chunk's root with the cells above the
// chunks, and the levels below across all chunks. So walking the prototype breadth-first, the
// levels down to one below the chunk roots (about 5 records per chunk for a terrain, 6 with the
// cells above) fill their pages as if it had been built in one piece: a page per
// nodesPerPage - 7 records (a sibling block of up to 8 that does not fit starts a page), plus
// one for the root.
TEST(SceneBuilderTest, ChunksTopLevelsSharePagesWithTheCellsAboveThem) {
    const fs::path dir = freshTestDir();
    constexpr unsigned kThreads = 4;
    const BuildReport report = buildOrFail(generate("terrain:triangles=120000"), dir / "t.ffs", smallOptions(kThreads));
    ASSERT_GE(report.chunks, 16u) << buildReportJson(report);
    Result<std::unique_ptr<storage::SceneFile>> opened = storage::SceneFile::open(dir / "t.ffs");
    ASSERT_TRUE(opened.isOk()) << opened.status().toString();
    const storage::SceneFile& file = **opened;
    const std::uint64_t perPage = storage::nodesPerPage(file.pageSize());
    std::vector<std::vector<WalkedNode>> levels;
    ASSERT_NO_FATAL_FAILURE(walkLevels(file, file.prototypes()[0].root, levels));

    std::set<std::uint32_t> pages;
    std::uint64_t nodes = 0;
    for (std::size_t depth = 0; depth < levels.size() && nodes + levels[depth].size() <= 6 * report.chunks; ++depth) {
        for (const WalkedNode& node : levels[depth])
            pages.insert(node.ref.page);
        nodes += levels[depth].size();
        EXPECT_LE(pages.size(), (nodes + perPage - 8) / (perPage - 7) + 1)
                << nodes << " records down to depth " << depth << ", " << report.chunks << " chunks";
    }
    EXPECT_GT(nodes, 4 * report.chunks); // the walk reached below the chunk roots
}

// Below the chunk roots too, a chunked prototype is laid out as if built in one piece: each level's
// records and triangles, across all chunks, fill shared pages. Written chunk by chunk instead,
// a level would cost at least a page per chunk that has records (triangles) there, however few
// (docs/results/paging.md, "Chunks"). At each depth of a breadth-first walk, the records sit in
// at most a page per nodesPerPage - 7 records (a sibling block of up to 8 that does not fit
// starts a page) and the triangle runs in a page per trianglesPerPage triangles, plus two for
// where the level starts in its region and the part of it kept with the cells above the chunks.
// The triangles are written in extents (budget/256 here: 16 pages) that a run never crosses, so
// each extent may leave up to its level's longest run empty at its end.
TEST(SceneBuilderTest, ChunkedPrototypeFillsPagesLevelByLevelAcrossChunks) {
    const fs::path dir = freshTestDir();
    constexpr unsigned kThreads = 4;
    const RecordingSink scene = generate("terrain:triangles=120000");
    const BuildReport report = buildOrFail(scene, dir / "t.ffs", smallOptions(kThreads));
    ASSERT_GE(report.chunks, 16u) << buildReportJson(report);
    expectSceneMatches(dir / "t.ffs", scene, report);
    Result<std::unique_ptr<storage::SceneFile>> opened = storage::SceneFile::open(dir / "t.ffs");
    ASSERT_TRUE(opened.isOk()) << opened.status().toString();
    const storage::SceneFile& file = **opened;
    const std::uint64_t nodesPerPage = storage::nodesPerPage(file.pageSize());
    const std::uint64_t trianglesPerPage = storage::trianglesPerPage(file.pageSize());
    const std::uint64_t extentTriangles = SceneBuilder::kMinimumBudgetBytes / 256 / file.pageSize() * trianglesPerPage;
    std::vector<std::vector<WalkedNode>> levels;
    ASSERT_NO_FATAL_FAILURE(walkLevels(file, file.prototypes()[0].root, levels));
    EXPECT_GE(levels.size(), 8u); // the walk goes through the chunks to their leaves

    for (std::size_t depth = 0; depth < levels.size(); ++depth) {
        std::set<std::uint32_t> nodePages;
        std::set<std::uint64_t> geometryPages;
        std::uint64_t triangles = 0;
        std::uint64_t longestRun = 0;
        for (const WalkedNode& node : levels[depth]) {
            nodePages.insert(node.ref.page);
            std::vector<storage::GeometrySegment> runs;
            const Status status = file.geometrySegments(node.record, runs);
            ASSERT_TRUE(status.isOk()) << status.toString();
            for (const storage::GeometrySegment& run : runs)
                geometryPages.insert(run.page);
            triangles += node.record.geometryCount;
            longestRun = std::max<std::uint64_t>(longestRun, node.record.geometryCount);
        }
        const std::uint64_t records = levels[depth].size();
        EXPECT_LE(nodePages.size(), (records + nodesPerPage - 8) / (nodesPerPage - 7) + 2)
                << records << " records at depth " << depth << ", " << report.chunks << " chunks";
        ASSERT_LT(longestRun, extentTriangles / 2);
        const std::uint64_t extents = (triangles + extentTriangles - longestRun - 1) / (extentTriangles - longestRun);
        const std::uint64_t slots = triangles + extents * longestRun;
        EXPECT_LE(geometryPages.size(), (slots + trianglesPerPage - 1) / trianglesPerPage + 2)
                << triangles << " triangles at depth " << depth << " in " << extents << " extents, " << report.chunks
                << " chunks";
    }
}

// A triangle wider than a cell stops at it; when that cell is a chunk root it must go into the
// chunk (whose octree keeps it at its root) rather than into the cell above it.
TEST(SceneBuilderTest, LargeTriangleAloneInAChunkCellIsStored) {
    const fs::path dir = freshTestDir();
    constexpr unsigned kThreads = 8;
    const std::size_t clusterSize = chunkTriangles(kThreads) + chunkTriangles(kThreads) / 4;
    // Root cell ~[0, 2]^3; clusters in octants 0 and 7 are bigger than a chunk.
    std::vector<storage::PackedTriangle> triangles =
            cluster(clusterSize, glm::vec3(0.0f), glm::vec3(0.4f), 1);
    const auto far = cluster(clusterSize, glm::vec3(1.6f), glm::vec3(2.0f), 2);
    triangles.insert(triangles.end(), far.begin(), far.end());
    // Centroid in octant 3 (x+, y+, z-), 1.05 wide: wider than the 1.0 cell of that octant.
    triangles.push_back(packTriangle(
            vertexAt({0.95f, 1.3f, 0.3f}),
            vertexAt({2.0f, 1.5f, 0.4f}),
            vertexAt({1.2f, 1.4f, 0.2f})));
    const RecordingSink scene = singlePrototypeScene(triangles);
    const BuildReport report = buildOrFail(scene, dir / "scene.ffs", smallOptions(kThreads));
    EXPECT_GT(report.chunks, 2u);
    expectSceneMatches(dir / "scene.ffs", scene, report);
}

// A chunk's root waits in memory for the tree above the chunks, but its triangles (here 2,000 that
// all stop at one chunk's root) go to its level's pages, and the root's record must point there.
TEST(SceneBuilderTest, TrianglesAtAChunkRootAreStoredWithItsLevel) {
    const fs::path dir = freshTestDir();
    constexpr unsigned kThreads = 1;
    const std::size_t clusterSize = chunkTriangles(kThreads) + chunkTriangles(kThreads) / 4;
    std::vector<storage::PackedTriangle> triangles = cluster(clusterSize, glm::vec3(0.0f), glm::vec3(0.4f), 1);
    const auto far = cluster(clusterSize, glm::vec3(1.6f), glm::vec3(2.0f), 2);
    triangles.insert(triangles.end(), far.begin(), far.end());
    // Centroids in octant 3 (x+, y+, z-), 1.05 wide: wider than that octant's 1.0 cell, so all
    // of them stop at the root of the chunk that octant becomes.
    constexpr int kLarge = 2000;
    for (int k = 0; k < kLarge; ++k) {
        const float dz = 1e-4f * static_cast<float>(k);
        triangles.push_back(packTriangle(
                vertexAt({0.95f, 1.3f, 0.3f + dz}), vertexAt({2.0f, 1.5f, 0.4f + dz}), vertexAt({1.2f, 1.4f, 0.2f + dz})));
    }
    const RecordingSink scene = singlePrototypeScene(triangles);
    const BuildReport report = buildOrFail(scene, dir / "scene.ffs", smallOptions(kThreads));
    EXPECT_GT(report.chunks, 2u);
    expectSceneMatches(dir / "scene.ffs", scene, report);
}

// A counted cell whose only triangle stops in a cell above it must not become an empty chunk.
TEST(SceneBuilderTest, CellWhoseTrianglesStopAboveItBecomesNoChunk) {
    const fs::path dir = freshTestDir();
    constexpr unsigned kThreads = 8;
    const std::size_t clusterSize = chunkTriangles(kThreads) + chunkTriangles(kThreads) / 4;
    std::vector<storage::PackedTriangle> triangles =
            cluster(clusterSize, glm::vec3(0.0f), glm::vec3(0.9f), 1);
    const auto far = cluster(clusterSize, glm::vec3(1.55f), glm::vec3(2.0f), 2);
    triangles.insert(triangles.end(), far.begin(), far.end());
    // Centroid in octant 7, sub-octant 0 ([1, 1.5]^3), 1.05 wide: stops at the octant-7 cell,
    // which holds too many triangles to be a chunk itself.
    triangles.push_back(packTriangle(
            vertexAt({0.95f, 1.0f, 0.95f}),
            vertexAt({2.0f, 1.2f, 1.0f}),
            vertexAt({1.0f, 1.2f, 2.0f})));
    const RecordingSink scene = singlePrototypeScene(triangles);
    const BuildReport report = buildOrFail(scene, dir / "scene.ffs", smallOptions(kThreads));
    EXPECT_GT(report.chunks, 2u);
    expectSceneMatches(dir / "scene.ffs", scene, report);
}

// Clusters far denser than the scene's average: the first counting level cannot split them into
// chunks, a finer one can.
TEST(SceneBuilderTest, DenseClustersArePartitionedAtAFinerLevel) {
    const fs::path dir = freshTestDir();
    constexpr unsigned kThreads = 8;
    const std::size_t clusterSize = chunkTriangles(kThreads) + chunkTriangles(kThreads) / 4;
    std::vector<storage::PackedTriangle> triangles =
            cluster(clusterSize, glm::vec3(0.0f), glm::vec3(0.05f), 1);
    const auto far = cluster(clusterSize, glm::vec3(1.95f), glm::vec3(2.0f), 2);
    triangles.insert(triangles.end(), far.begin(), far.end());
    const RecordingSink scene = singlePrototypeScene(triangles);
    const BuildReport report = buildOrFail(scene, dir / "scene.ffs", smallOptions(kThreads));
    EXPECT_GT(report.chunks, 2u);
    expectSceneMatches(dir / "scene.ffs", scene, report);
}

// ---- options ---------------------------------------------------------------------------------

TEST(SceneBuilderTest, RejectsInvalidOptions) {
    const fs::path dir = freshTestDir();
    auto expectInvalid = [&](const BuildOptions& options, const std::string& what) {
        Result<std::unique_ptr<SceneBuilder>> builder =
                SceneBuilder::create(dir / "scene.ffs", options);
        ASSERT_FALSE(builder.isOk()) << what;
        EXPECT_EQ(builder.status().code(), ErrorCode::InvalidArgument) << what;
        EXPECT_NE(builder.status().message().find(what), std::string::npos)
                << builder.status().message();
    };
    BuildOptions options = smallOptions();
    options.memoryBudgetBytes = SceneBuilder::kMinimumBudgetBytes - 1;
    expectInvalid(options, "budget");
    options.memoryBudgetBytes = 0;
    expectInvalid(options, "budget");
    for (std::uint32_t pageSize : {0u, 1000u, 4095u, 6000u, 65537u, 32u << 20}) {
        options = smallOptions();
        options.pageSize = pageSize;
        expectInvalid(options, "page size");
    }
    for (int resolution : {-1, 0, 1, 65}) {
        options = smallOptions();
        options.hierarchy.bakeResolution = resolution;
        expectInvalid(options, "bake resolution");
    }
    options = smallOptions();
    options.hierarchy.cubeCost = 0.0f;
    expectInvalid(options, "cube cost");
    options = smallOptions();
    options.hierarchy.largeTriangleTolerance = std::numeric_limits<float>::quiet_NaN();
    expectInvalid(options, "tolerance");
    EXPECT_TRUE(listDirectory(dir).empty());
}

// ---- failures and temporary files ------------------------------------------------------------

TEST(SceneBuilderTest, EmptySceneFailsAndLeavesNothingBehind) {
    const fs::path dir = freshTestDir();
    RecordingSink noPrototypes;
    RecordingSink noTriangles;
    const PrototypeId id = noTriangles.addPrototype("empty").value();
    ASSERT_TRUE(noTriangles.addInstance(id, glm::mat4(1.0f)).isOk());
    RecordingSink onlyDropped;
    const PrototypeId dropped = onlyDropped.addPrototype("flat").value();
    const storage::PackedTriangle flat = packTriangle(
            vertexAt(glm::vec3(0.0f)), vertexAt(glm::vec3(1.0f)), vertexAt(glm::vec3(2.0f)));
    ASSERT_TRUE(onlyDropped.addTriangles(dropped, std::span(&flat, 1)).isOk());
    ASSERT_TRUE(onlyDropped.addInstance(dropped, glm::mat4(1.0f)).isOk());

    for (const RecordingSink* scene : {&noPrototypes, &noTriangles, &onlyDropped}) {
        Result<std::unique_ptr<SceneBuilder>> builder =
                SceneBuilder::create(dir / "scene.ffs", smallOptions());
        ASSERT_TRUE(builder.isOk()) << builder.status().toString();
        ASSERT_TRUE(replay(*scene, **builder).isOk());
        Result<BuildReport> report = (*builder)->finish();
        ASSERT_FALSE(report.isOk());
        EXPECT_EQ(report.status().code(), ErrorCode::InvalidInput);
        EXPECT_NE(report.status().message().find("no triangles"), std::string::npos)
                << report.status().toString();
        // "Temporary files are removed either way": already when finish() returns.
        EXPECT_EQ(listDirectory(dir), std::vector<std::string>{});
        builder.value().reset();
        EXPECT_EQ(listDirectory(dir), std::vector<std::string>{});
    }
}

TEST(SceneBuilderTest, FinishTwiceIsAnError) {
    const fs::path dir = freshTestDir();
    const RecordingSink scene =
            singlePrototypeScene(cluster(10, glm::vec3(0.0f), glm::vec3(1.0f), 1));
    Result<std::unique_ptr<SceneBuilder>> builder =
            SceneBuilder::create(dir / "scene.ffs", smallOptions());
    ASSERT_TRUE(builder.isOk());
    ASSERT_TRUE(replay(scene, **builder).isOk());
    ASSERT_TRUE((*builder)->finish().isOk());
    EXPECT_EQ((*builder)->finish().status().code(), ErrorCode::InvalidArgument);
    EXPECT_TRUE(fs::exists(dir / "scene.ffs"));
}

TEST(SceneBuilderTest, TemporaryDirectoryIsRemovedAfterSuccessAndFailure) {
    const fs::path dir = freshTestDir();
    const fs::path spill = dir / "spill";
    fs::create_directories(spill);
    fs::create_directories(dir / "out");
    // Enough triangles that run files reach the disk (spill buffers are budget / 8).
    const RecordingSink scene = generate("terrain:triangles=60000");
    BuildOptions options = smallOptions(4);

    // Success, temporary files beside the output.
    buildOrFail(scene, dir / "out" / "beside.ffs", options);
    EXPECT_EQ(listDirectory(dir / "out"), std::vector<std::string>{"beside.ffs"});

    // Success, temporary files in their own directory.
    options.tempDirectory = spill;
    const BuildReport report = buildOrFail(scene, dir / "out" / "apart.ffs", options);
    EXPECT_GT(report.spillBytes, 0u);
    EXPECT_EQ(listDirectory(spill), std::vector<std::string>{});
    EXPECT_EQ(listDirectory(dir / "out"), (std::vector<std::string>{"apart.ffs", "beside.ffs"}));

    // Failure in finish(): triangles but no instance to draw them.
    RecordingSink noInstances;
    const PrototypeId id = noInstances.addPrototype("mesh").value();
    ASSERT_TRUE(noInstances.addTriangles(id, scene.prototypes()[0].triangles).isOk());
    EXPECT_FALSE(buildScene(noInstances, dir / "out" / "failed.ffs", options).isOk());
    EXPECT_EQ(listDirectory(spill), std::vector<std::string>{});
    EXPECT_EQ(listDirectory(dir / "out"), (std::vector<std::string>{"apart.ffs", "beside.ffs"}));

    // A builder dropped before finish(), e.g. because its source failed half way.
    {
        Result<std::unique_ptr<SceneBuilder>> builder =
                SceneBuilder::create(dir / "out" / "abandoned.ffs", options);
        ASSERT_TRUE(builder.isOk());
        ASSERT_TRUE(replay(scene, **builder).isOk());
        EXPECT_FALSE(listDirectory(spill).empty()) << "run files should have reached the disk";
    }
    EXPECT_EQ(listDirectory(spill), std::vector<std::string>{});
    EXPECT_EQ(listDirectory(dir / "out"), (std::vector<std::string>{"apart.ffs", "beside.ffs"}));
}

// Distinct instances must be usable at the same time (STYLE.md §6), also in one directory.
TEST(SceneBuilderTest, TwoBuildersInOneDirectoryKeepTheirTemporaryFilesApart) {
    const fs::path dir = freshTestDir();
    const RecordingSink first =
            singlePrototypeScene(cluster(50000, glm::vec3(0.0f), glm::vec3(1.0f), 1));
    const RecordingSink second =
            singlePrototypeScene(cluster(50000, glm::vec3(5.0f), glm::vec3(6.0f), 2));
    const BuildOptions options = smallOptions(2);
    Result<std::unique_ptr<SceneBuilder>> a = SceneBuilder::create(dir / "first.ffs", options);
    Result<std::unique_ptr<SceneBuilder>> b = SceneBuilder::create(dir / "second.ffs", options);
    ASSERT_TRUE(a.isOk() && b.isOk());
    ASSERT_TRUE(replay(first, **a).isOk());
    ASSERT_TRUE(replay(second, **b).isOk());
    Result<BuildReport> reportA = (*a)->finish();
    ASSERT_TRUE(reportA.isOk()) << reportA.status().toString();
    Result<BuildReport> reportB = (*b)->finish();
    ASSERT_TRUE(reportB.isOk()) << reportB.status().toString();
    expectSceneMatches(dir / "first.ffs", first, *reportA);
    expectSceneMatches(dir / "second.ffs", second, *reportB);
    EXPECT_EQ(listDirectory(dir), (std::vector<std::string>{"first.ffs", "second.ffs"}));
}

} // namespace
} // namespace ff::builder
