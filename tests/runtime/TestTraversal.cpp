// BackToFrontTraversal against fake page access, visibility, upload gates and a recording sink:
// deferral, request priorities, prefetch's lower priority, occlusion answers, refused uploads,
// bounded batches that keep the cubes' order, and a cut of 1.7 * 10^7 cubes drawn in bounded
// memory. Scenes: a small generated sphere (real pages, built on disk) and synthetic recursive
// instancing written with SceneWriter (a few pages that expand to any cut size).

#include "RecordingSink.h"
#include "TestDir.h"

#include <ff/builder/Generators.h>
#include <ff/builder/SceneBuilder.h>
#include <ff/runtime/BackToFrontTraversal.h>
#include <ff/storage/ProcessMemory.h>
#include <ff/storage/SceneFile.h>
#include <ff/storage/SceneWriter.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <tuple>
#include <vector>

namespace ff::runtime {
namespace {

namespace fs = std::filesystem;

using test::freshDir;

/** The memory map, except that `pending` pages are not resident yet; records every lookup. */
class FakePageAccess final : public IPageAccess {
public:
    explicit FakePageAccess(const storage::SceneFile& scene)
        : mMapped(scene) {}
    PageLookup lookup(std::uint64_t page, storage::PageType type, float priority) override {
        lookups.push_back({page, type, priority});
        if (pending.contains(page))
            return {PageAvailability::Pending, {}, nullptr};
        return mMapped.lookup(page, type, priority);
    }
    /** The highest priority a pending page was asked for with (-1: none was looked up). */
    float topPendingPriority() const {
        float best = -1.0f;
        for (const Lookup& l : lookups)
            if (pending.contains(l.page))
                best = std::max(best, l.priority);
        return best;
    }

    struct Lookup {
        std::uint64_t page;
        storage::PageType type;
        float priority;
    };
    std::set<std::uint64_t> pending;
    std::vector<Lookup> lookups;

private:
    MappedPageAccess mMapped;
};

/** Occludes the keys it is given, says an earlier walk met `walked`'s cubes below theirs and went
 *  through `walkedWhole`'s subtrees without keeping their cubes; remembers what it was asked. */
class FakeVisibility final : public IVisibility {
public:
    Visibility visibility(const NodeKey& key) const override {
        for (const NodeKey& k : occluded)
            if (k == key)
                return Visibility::Occluded;
        return Visibility::Visible;
    }
    Known known(const NodeKey& key) const override {
        asked.push_back(key);
        for (const auto& [k, cubes] : walked)
            if (k == key)
                return {visibility(key), true, true, cubes};
        if (std::find(walkedWhole.begin(), walkedWhole.end(), key) != walkedWhole.end())
            return {visibility(key), true, false, {}};
        return {visibility(key), false, false, {}};
    }
    std::vector<NodeKey> occluded;
    std::vector<std::pair<NodeKey, std::vector<MetCube>>> walked;
    std::vector<NodeKey> walkedWhole;
    mutable std::vector<NodeKey> asked;
};

class RefuseAll final : public IUploadGate {
public:
    bool admit(std::uint64_t) override { return false; }
};

std::unique_ptr<storage::SceneFile>
buildGenerated(const fs::path& file, const std::string& generator) {
    builder::BuildOptions options;
    options.memoryBudgetBytes = builder::SceneBuilder::kMinimumBudgetBytes;
    // Format 1 until this test is ported to format 2 (issue 16: version 1 is to be refused).
    options.formatVersion = storage::kFormatVersion;
    auto sceneBuilder = builder::SceneBuilder::create(file, options);
    EXPECT_TRUE(sceneBuilder.isOk()) << sceneBuilder.status().toString();
    auto spec = builder::parseGeneratorSpec(generator);
    EXPECT_TRUE(spec.isOk()) << spec.status().toString();
    EXPECT_TRUE(builder::runGenerator(*spec, **sceneBuilder).isOk());
    EXPECT_TRUE((*sceneBuilder)->finish().isOk());
    auto opened = storage::SceneFile::open(file);
    EXPECT_TRUE(opened.isOk()) << opened.status().toString();
    return opened ? std::move(*opened) : nullptr;
}

Bounds boundsOf(const storage::SceneFile& scene) {
    const auto& h = scene.header();
    return {{h.boundsMin[0], h.boundsMin[1], h.boundsMin[2]},
            {h.boundsMax[0], h.boundsMax[1], h.boundsMax[2]}};
}

FrameContext frameAt(const storage::SceneFile& scene, float distanceRadii, float epsilon) {
    FrameContext frame;
    frame.camera = Camera::orbit(boundsOf(scene), distanceRadii, 30.0f, 20.0f, 0.7853982f);
    frame.camera.fitClipPlanes(boundsOf(scene));
    frame.selection.epsilonPixels = epsilon;
    return frame;
}

struct Walk {
    test::RecordingSink sink;
    FrameStats stats;
    Status status;
};

Walk walk(
        const storage::SceneFile& scene,
        IPageAccess& pages,
        const FrameContext& frame,
        IVisibility* visibility = nullptr,
        IUploadGate* gate = nullptr,
        bool keep = true) {
    BackToFrontTraversal traversal(scene, pages);
    NoVisibility none;
    AdmitAll admitAll;
    Walk w{test::RecordingSink(keep), {}, Status::ok()};
    w.status = traversal.traverse(
            frame, {w.sink, visibility ? *visibility : none, gate ? *gate : admitAll}, w.stats);
    return w;
}

/** A cubes-only walk (OcclusionTraversal's pass 2) that keeps what it draws. */
Walk walkCubesOnly(
        const storage::SceneFile& scene,
        IPageAccess& pages,
        const FrameContext& frame,
        IVisibility& visibility) {
    BackToFrontTraversal traversal(scene, pages);
    traversal.setCubesOnly(true);
    AdmitAll admitAll;
    Walk w{test::RecordingSink(true), {}, Status::ok()};
    w.status = traversal.traverse(frame, {w.sink, visibility, admitAll}, w.stats);
    return w;
}

class SphereTraversalTest : public ::testing::Test {
protected:
    void SetUp() override {
        mScene = buildGenerated(freshDir() / "sphere.ffs", "sphere:triangles=20000");
        ASSERT_TRUE(mScene);
        auto root = mScene->node(mScene->header().root);
        ASSERT_TRUE(root.isOk());
        mRoot = *root;
        ASSERT_GT(mRoot.childCount, 0u);
        const std::uint64_t rootPage = mScene->header().root.page;
        for (std::uint64_t p = 1; p < mScene->pageCount(); ++p)
            if (p != rootPage)
                mAllButRoot.insert(p);
    }
    std::unique_ptr<storage::SceneFile> mScene;
    storage::NodeRecord mRoot{};
    std::set<std::uint64_t> mAllButRoot;
};

// Cells whose children or triangles are not resident are drawn as their cubes, counted as
// debt, and their pages are asked for; nothing waits.
TEST_F(SphereTraversalTest, MissingPagesDeferToTheCellsCubesAndAreAskedFor) {
    FakePageAccess pages(*mScene);
    pages.pending = mAllButRoot;
    const Walk w = walk(*mScene, pages, frameAt(*mScene, 2.0f, 1.0f));
    ASSERT_TRUE(w.status.isOk()) << w.status.toString();
    EXPECT_GT(w.stats.nodesDeferred, 0u);
    EXPECT_EQ(w.sink.cubes.size(), w.stats.nodesDeferred)
            << "each deferred cell stands in with its cube";
    for (const test::RecordedRun& r : w.sink.runs)
        EXPECT_FALSE(pages.pending.contains(r.run.page))
                << "drawn from a page that is not resident";
    EXPECT_GT(pages.topPendingPriority(), 0.0f);

    pages.pending.clear();
    const Walk resident = walk(*mScene, pages, frameAt(*mScene, 2.0f, 1.0f));
    EXPECT_EQ(resident.stats.nodesDeferred, 0u);
    EXPECT_GT(resident.stats.nodesVisited, w.stats.nodesVisited) << "refined once resident";
}

// Pages are asked for by projected size: the same page matters more from nearer, and the
// prefetch walk (priorityScale 1/4) asks for it at a quarter of the frame's priority.
TEST_F(SphereTraversalTest, RequestPrioritiesFollowProjectedSizeAndPrefetchAsksAtAQuarter) {
    const auto priorityAt = [&](float distance, float scale) {
        FakePageAccess pages(*mScene);
        pages.pending = mAllButRoot;
        FrameContext frame = frameAt(*mScene, distance, 1.0f);
        frame.selection.priorityScale = scale;
        EXPECT_TRUE(walk(*mScene, pages, frame).status.isOk());
        return pages.topPendingPriority();
    };
    const float near = priorityAt(1.5f, 1.0f);
    const float far = priorityAt(6.0f, 1.0f);
    EXPECT_GT(near, far);
    EXPECT_GT(far, 0.0f);
    EXPECT_FLOAT_EQ(priorityAt(1.5f, 0.25f), 0.25f * near);
}

TEST_F(SphereTraversalTest, AnOccludedNodeIsSkippedAndCounted) {
    FakePageAccess pages(*mScene);
    FakeVisibility visibility;
    const Walk visible = walk(*mScene, pages, frameAt(*mScene, 2.0f, 1.0f), &visibility);
    ASSERT_TRUE(visible.status.isOk());
    EXPECT_EQ(visible.stats.nodesOccluded, 0u);
    EXPECT_GT(visible.sink.runs.size() + visible.sink.cubes.size(), 0u);

    visibility.occluded.push_back({0, mScene->header().root});
    const Walk occluded = walk(*mScene, pages, frameAt(*mScene, 2.0f, 1.0f), &visibility);
    ASSERT_TRUE(occluded.status.isOk());
    EXPECT_EQ(occluded.stats.nodesOccluded, 1u);
    EXPECT_EQ(occluded.stats.nodesVisited, 1u);
    EXPECT_TRUE(occluded.sink.runs.empty());
    EXPECT_TRUE(occluded.sink.cubes.empty());
}

// Geometry the GPU may not upload this frame is treated like a page still on disk.
TEST_F(SphereTraversalTest, RefusedUploadsDrawCubesInsteadOfTriangles) {
    FakePageAccess pages(*mScene);
    RefuseAll refuse;
    const Walk w = walk(*mScene, pages, frameAt(*mScene, 2.0f, 0.0f), nullptr, &refuse);
    ASSERT_TRUE(w.status.isOk());
    EXPECT_TRUE(w.sink.runs.empty());
    EXPECT_EQ(w.stats.trianglesDrawn, 0u);
    EXPECT_GT(w.stats.uploadsRefused, 0u);
    EXPECT_GT(w.stats.nodesDeferred, 0u);
    EXPECT_EQ(w.sink.cubes.size(), w.stats.cubesDrawn);
    EXPECT_GT(w.sink.cubes.size(), 0u);
}

/** Triangles per (page, first triangle) and transform: what was drawn, however it was merged. */
std::map<std::tuple<std::uint64_t, std::uint32_t, float>, std::uint64_t>
trianglesDrawn(const test::RecordingSink& s) {
    std::map<std::tuple<std::uint64_t, std::uint32_t, float>, std::uint64_t> out;
    for (const test::RecordedRun& r : s.runs)
        for (std::uint32_t t = 0; t < r.run.count; ++t)
            ++out[{r.run.page,
                   r.run.first + t,
                   r.transform[3][0] + 3.0f * r.transform[0][0]}];
    return out;
}

// Tiny batches draw exactly what one batch draws: the same triangles, and the same cubes in
// the same order, all of them after all the geometry.
TEST_F(SphereTraversalTest, BoundedBatchesDrawWhatOneBatchDrawsInTheSameOrder) {
    FakePageAccess pages(*mScene);
    FrameContext frame = frameAt(*mScene, 10.0f, 4.0f);
    frame.selection.cubeStyle = CubeStyle::Faces;
    frame.budgets.drawBatchBytes = SIZE_MAX;
    const Walk one = walk(*mScene, pages, frame);
    ASSERT_EQ(one.sink.batches, 1u);
    ASSERT_GT(one.sink.cubes.size(), 20u) << "a mix of cubes and geometry";
    ASSERT_GT(one.sink.runs.size(), 0u);

    frame.budgets.drawBatchBytes = 1024;
    const Walk many = walk(*mScene, pages, frame);
    ASSERT_TRUE(many.status.isOk());
    EXPECT_GT(many.sink.batches, 10u);
    EXPECT_FALSE(many.sink.geometryAfterCubes);
    EXPECT_LE(
            many.sink.maxBatchBytes,
            1024u + sizeof(CubeDraw) + sizeof(glm::mat4) + sizeof(glm::vec3));
    EXPECT_EQ(trianglesDrawn(many.sink), trianglesDrawn(one.sink));
    ASSERT_EQ(many.sink.cubes.size(), one.sink.cubes.size());
    for (std::size_t i = 0; i < one.sink.cubes.size(); ++i) {
        EXPECT_EQ(many.sink.cubes[i].cube.boxMin, one.sink.cubes[i].cube.boxMin) << i;
        EXPECT_EQ(many.sink.cubes[i].transform, one.sink.cubes[i].transform) << i;
    }
    EXPECT_EQ(many.stats.cubesDrawn, one.stats.cubesDrawn) << "counted once, not per pass";
    EXPECT_EQ(many.stats.trianglesDrawn, one.stats.trianglesDrawn);
    EXPECT_EQ(many.stats.nodesVisited, one.stats.nodesVisited);
}

// ---- A synthetic cut: recursive instancing ------------------------------------------------
// Prototype 0 is a unit cube cell with 8 octant leaves, each a colour cube. Prototype k (and the
// scene's root, one level up) is a unit cell whose 8 octant children are instances of prototype
// k - 1 scaled by 1/2. With `levels` levels of instancing the scene is a few pages, and its cut
// at any ε is 8^(levels + 1) leaf cubes.

storage::NodeRecord unitCell(float lo, float hi) {
    storage::NodeRecord n{};
    n.cellMin = n.boundsMin = {lo, lo, lo};
    n.cellMax = n.boundsMax = {hi, hi, hi};
    n.kind = static_cast<std::uint8_t>(storage::NodeKind::Cell);
    return n;
}

std::array<float, 3> octantMin(int o) {
    return {0.5f * static_cast<float>(o & 1),
            0.5f * static_cast<float>((o >> 1) & 1),
            0.5f * static_cast<float>((o >> 2) & 1)};
}

template <typename T> std::vector<std::byte> bytesOf(const std::vector<T>& items) {
    std::vector<std::byte> bytes(items.size() * sizeof(T));
    std::memcpy(bytes.data(), items.data(), bytes.size());
    return bytes;
}

std::unique_ptr<storage::SceneFile> writeRecursiveScene(const fs::path& path, int levels) {
    auto writer = storage::SceneWriter::create(path);
    EXPECT_TRUE(writer.isOk()) << writer.status().toString();
    storage::SceneWriter& w = **writer;
    std::vector<storage::PrototypeRecord> prototypes;
    std::vector<storage::InstanceRecord> instances;
    std::uint64_t nodes = 0;
    // Each prototype: one Nodes page, the root at slot 0 and its 8 children at slots 1..8.
    for (int level = 0; level <= levels; ++level) {
        const auto page = static_cast<std::uint32_t>(w.nextPageIndex());
        std::vector<storage::NodeRecord> records(9);
        records[0] = unitCell(0.0f, 1.0f);
        records[0].childCount = 8;
        records[0].firstChild = {page, 1};
        for (int o = 0; o < 8; ++o) {
            storage::NodeRecord& child = records[static_cast<std::size_t>(1 + o)];
            child = unitCell(0.0f, 0.5f);
            const std::array<float, 3> lo = octantMin(o);
            for (std::size_t a = 0; a < 3; ++a) {
                child.cellMin[a] = child.boundsMin[a] = lo[a];
                child.cellMax[a] = child.boundsMax[a] = lo[a] + 0.5f;
            }
            child.level = 1;
            if (level == 0) {
                child.flags = storage::kNodeHasCube;
                for (auto& face : child.cube)
                    face = {static_cast<std::uint8_t>(30 * o), 90, 160, 255};
            } else {
                child.kind = static_cast<std::uint8_t>(storage::NodeKind::Instance);
                child.geometryPage = static_cast<std::uint32_t>(instances.size());
                storage::InstanceRecord instance{};
                instance.transform = {0.5f, 0, 0, lo[0], 0, 0.5f, 0, lo[1], 0, 0, 0.5f, lo[2]};
                instance.prototype = static_cast<std::uint32_t>(level - 1);
                instances.push_back(instance);
            }
        }
        EXPECT_TRUE(w.appendPage(storage::PageType::Nodes, bytesOf(records)).isOk());
        nodes += records.size();
        storage::PrototypeRecord prototype{};
        prototype.root = {page, 0};
        prototype.boundsMin = {0, 0, 0};
        prototype.boundsMax = {1, 1, 1};
        prototype.nodeCount = 9;
        prototypes.push_back(prototype);
    }
    std::vector<storage::SectionEntry> sections;
    auto protos = w.appendSection(
            storage::SectionType::Prototypes, bytesOf(prototypes), prototypes.size());
    auto insts =
            w.appendSection(storage::SectionType::Instances, bytesOf(instances), instances.size());
    EXPECT_TRUE(protos.isOk() && insts.isOk());
    sections = {*protos, *insts};
    storage::SectionEntry hierarchy{};
    hierarchy.type = static_cast<std::uint32_t>(storage::SectionType::Hierarchy);
    hierarchy.firstPage = 1;
    hierarchy.pageCount = static_cast<std::uint64_t>(levels + 1);
    hierarchy.itemCount = nodes;
    sections.push_back(hierarchy);
    storage::FileHeader header{};
    header.root = prototypes.back().root;
    header.boundsMin = {0, 0, 0};
    header.boundsMax = {1, 1, 1};
    header.nodeCount = nodes;
    EXPECT_TRUE(w.commit(header, sections).isOk());
    auto opened = storage::SceneFile::open(path);
    EXPECT_TRUE(opened.isOk()) << opened.status().toString();
    return opened ? std::move(*opened) : nullptr;
}

FrameContext wholeCut() {
    FrameContext frame;
    frame.camera = Camera::lookAt({0.5f, 0.6f, 3.0f}, {0.5f, 0.5f, 0.5f}, {0, 1, 0}, 0.7853982f);
    frame.camera.fitClipPlanes({{0, 0, 0}, {1, 1, 1}});
    frame.selection.epsilonPixels = 1e9f; // every leaf is drawn as its cube
    frame.selection.cubeStyle = CubeStyle::Faces;
    return frame;
}

TEST(SyntheticCutTest, RecursiveInstancingDrawsEveryLeafInBackToFrontOrder) {
    const auto scene = writeRecursiveScene(freshDir() / "recursive.ffs", 2);
    ASSERT_TRUE(scene);
    MappedPageAccess pages(*scene);
    FrameContext frame = wholeCut();
    const Walk one = walk(*scene, pages, frame);
    ASSERT_TRUE(one.status.isOk()) << one.status.toString();
    ASSERT_EQ(one.sink.cubes.size(), 512u);
    EXPECT_TRUE(one.sink.cubesAsFaces);
    EXPECT_EQ(one.stats.instancesEntered, 8u + 64u);
    // Back to front: the camera looks along -Z from z = 3, so the first cube lies in the far
    // (z = 0) corner layer and the last in the near one.
    const auto worldZ = [](const test::RecordedCube& c) {
        return glm::vec3(c.transform * glm::vec4(c.cube.boxMin, 1.0f)).z;
    };
    EXPECT_LT(worldZ(one.sink.cubes.front()), 0.25f);
    EXPECT_GE(worldZ(one.sink.cubes.back()), 0.75f);

    frame.budgets.drawBatchBytes = 2048;
    const Walk many = walk(*scene, pages, frame);
    ASSERT_EQ(many.sink.cubes.size(), one.sink.cubes.size());
    EXPECT_GT(many.sink.batches, 10u);
    for (std::size_t i = 0; i < one.sink.cubes.size(); ++i) {
        EXPECT_EQ(many.sink.cubes[i].transform, one.sink.cubes[i].transform) << i;
        EXPECT_EQ(many.sink.cubes[i].cube.boxMin, one.sink.cubes[i].cube.boxMin) << i;
    }
}

// OcclusionTraversal walks the subtrees too small to test whole in its first pass and hands the
// cubes it met there to the cubes-only walk, which draws them instead of walking there again:
// where the subtree's own cubes would come, in the frame each was met in.
TEST(SyntheticCutTest, ACubesOnlyWalkDrawsTheCubesAnEarlierWalkMetInsteadOfWalkingThere) {
    const auto scene = writeRecursiveScene(freshDir() / "recursive.ffs", 1);
    ASSERT_TRUE(scene);
    MappedPageAccess pages(*scene);
    const FrameContext frame = wholeCut();
    NoVisibility none;
    const Walk plain = walkCubesOnly(*scene, pages, frame, none);
    ASSERT_TRUE(plain.status.isOk()) << plain.status.toString();
    ASSERT_EQ(plain.sink.cubes.size(), 64u);
    // The root, its 8 instance nodes, and each instance's root and 8 leaves.
    EXPECT_EQ(plain.stats.nodesVisited, 1u + 8u + 8u * 9u);

    // The instance in octant 5, node slot 6 of the root's page; its 8 cubes in the plain walk.
    constexpr int kOctant = 5;
    const glm::vec3 at(0.5f, 0.0f, 0.5f); // octant 5: x and z high
    const auto inInstance = [&](const test::RecordedCube& c) {
        return glm::vec3(c.transform[3]) == at && c.transform[0][0] == 0.5f;
    };
    const auto first = std::find_if(plain.sink.cubes.begin(), plain.sink.cubes.end(), inInstance);
    ASSERT_NE(first, plain.sink.cubes.end());
    const auto begin = static_cast<std::size_t>(first - plain.sink.cubes.begin());
    ASSERT_TRUE(std::all_of(first, first + 8, inInstance)) << "an instance's cubes come together";

    FakeVisibility visibility;
    const std::array<std::uint8_t, 4> red{255, 0, 0, 255};
    std::vector<MetCube> met{
            {{{0.0f, 0.0f, 0.0f}, {0.1f, 0.1f, 0.1f}, 1, {red, red, red, red, red, red}}, 3, 1},
            {{{0.2f, 0.2f, 0.2f}, {0.3f, 0.3f, 0.3f}, 0, {red, red, red, red, red, red}}, 2, 1}};
    visibility.walked.push_back({{0, {scene->header().root.page, 1 + kOctant}}, met});
    const Walk taken = walkCubesOnly(*scene, pages, frame, visibility);
    ASSERT_TRUE(taken.status.isOk()) << taken.status.toString();
    EXPECT_EQ(taken.stats.nodesVisited, plain.stats.nodesVisited - 9u) << "not walked below it";
    ASSERT_EQ(taken.sink.cubes.size(), 64u - 8u + 2u);
    EXPECT_EQ(taken.stats.cubesDrawn, taken.sink.cubes.size());
    for (std::size_t i = 0; i < begin; ++i)
        EXPECT_EQ(taken.sink.cubes[i].cube.boxMin, plain.sink.cubes[i].cube.boxMin) << i;
    // Frame 1: the instance's, as its own cubes had; frame 0: the frame the node lies in.
    EXPECT_EQ(taken.sink.cubes[begin].cube.boxMin, met[0].draw.boxMin);
    EXPECT_EQ(taken.sink.cubes[begin].transform, first->transform);
    EXPECT_EQ(taken.sink.cubes[begin + 1].cube.boxMin, met[1].draw.boxMin);
    EXPECT_EQ(taken.sink.cubes[begin + 1].transform, glm::mat4(1.0f));
    for (std::size_t i = begin + 8; i < plain.sink.cubes.size(); ++i)
        EXPECT_EQ(taken.sink.cubes[i - 6].cube.boxMin, plain.sink.cubes[i].cube.boxMin) << i;
    // Its faces counted as it says, at its level.
    std::uint64_t perLevel = 0;
    for (std::uint64_t faces : taken.stats.cubeFacesPerLevel)
        perLevel += faces;
    EXPECT_EQ(perLevel, taken.stats.cubeFacesDrawn);
    EXPECT_GE(taken.stats.cubeFacesDrawn, 5u);
}

// Where the earlier walk went through a subtree whole but could not keep its cubes (its record is
// bounded), the cubes-only walk walks it again, and asks nothing below its root: no node there
// was tested or seen on its own (at the forest's edge, 677 k of 825 k lookups a frame).
TEST(SyntheticCutTest, ACubesOnlyWalkAsksNothingBelowANodeAnEarlierWalkWentThroughWhole) {
    const auto scene = writeRecursiveScene(freshDir() / "recursive.ffs", 1);
    ASSERT_TRUE(scene);
    MappedPageAccess pages(*scene);
    const FrameContext frame = wholeCut();
    FakeVisibility everywhere;
    const Walk plain = walkCubesOnly(*scene, pages, frame, everywhere);
    ASSERT_TRUE(plain.status.isOk()) << plain.status.toString();
    // The root, its 8 instance nodes and each instance's root: the leaves are cubes.
    ASSERT_EQ(everywhere.asked.size(), 1u + 8u + 8u);

    constexpr int kOctant = 5;
    const NodeKey instanceNode{0, {scene->header().root.page, 1 + kOctant}};
    FakeVisibility visibility;
    visibility.walkedWhole.push_back(instanceNode);
    const Walk taken = walkCubesOnly(*scene, pages, frame, visibility);
    ASSERT_TRUE(taken.status.isOk()) << taken.status.toString();
    EXPECT_EQ(visibility.asked.size(), everywhere.asked.size() - 1u) << "its instance's root";
    EXPECT_NE(std::find(visibility.asked.begin(), visibility.asked.end(), instanceNode), visibility.asked.end());
    for (const NodeKey& key : everywhere.asked) {
        if (std::find(visibility.asked.begin(), visibility.asked.end(), key) == visibility.asked.end()) {
            EXPECT_NE(key.instancePath, 0u) << "only what lies below the node is not asked";
        }
    }
    // Walked all the same: the same cubes, in the same order.
    EXPECT_EQ(taken.stats.nodesVisited, plain.stats.nodesVisited);
    ASSERT_EQ(taken.sink.cubes.size(), plain.sink.cubes.size());
    for (std::size_t i = 0; i < plain.sink.cubes.size(); ++i) {
        EXPECT_EQ(taken.sink.cubes[i].cube.boxMin, plain.sink.cubes[i].cube.boxMin) << i;
        EXPECT_EQ(taken.sink.cubes[i].transform, plain.sink.cubes[i].transform) << i;
    }
}

// The bound: a frame's transient memory stays under 64 MiB whatever the cut. Seven
// levels of instancing make a cut of 8^8 = 16.8 million cubes (870 MB as one list).
TEST(SyntheticCutTest, ACutOfSeventeenMillionCubesTakesUnder64MiB) {
    const auto scene = writeRecursiveScene(freshDir() / "recursive.ffs", 7);
    ASSERT_TRUE(scene);
    MappedPageAccess pages(*scene);
    const FrameContext frame = wholeCut();
    BackToFrontTraversal traversal(*scene, pages);
    NoVisibility none;
    AdmitAll admitAll;
    test::RecordingSink sink(false);
    FrameStats stats;
    const std::uint64_t anonBefore = storage::readProcessMemory().anonBytes;
    ASSERT_TRUE(traversal.traverse(frame, {sink, none, admitAll}, stats).isOk());
    const std::uint64_t anonAfter = storage::readProcessMemory().anonBytes;

    // What was measured, in the test's XML report (--gtest_output=xml).
    RecordProperty("scratch_bytes", std::to_string(traversal.scratchBytes()));
    RecordProperty("max_batch_bytes", std::to_string(sink.maxBatchBytes));
    RecordProperty("anon_growth_bytes", std::to_string(anonAfter - std::min(anonAfter, anonBefore)));
    RecordProperty("batches", std::to_string(sink.batches));
    constexpr std::uint64_t kCut = 1u << 24; // 8^8
    EXPECT_EQ(stats.cubesDrawn, kCut);
    EXPECT_EQ(sink.cubeCount, kCut);
    EXPECT_GT(sink.batches, 50u);
    EXPECT_LE(sink.maxBatchBytes, frame.budgets.drawBatchBytes + 256);
    constexpr std::uint64_t kBound = 64u << 20;
    EXPECT_LE(traversal.scratchBytes(), kBound);
    // The vectors keep their capacity after the frame, so what the traversal took is still
    // resident: the process grew by less than the bound.
    EXPECT_LE(anonAfter, anonBefore + kBound) << "before " << anonBefore << ", after " << anonAfter;
}

} // namespace
} // namespace ff::runtime
