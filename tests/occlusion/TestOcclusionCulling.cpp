// Occlusion culling drawn for real: the same frames with --occlusion on and off, side by side.
// What is behind a wall never reaches GL; what is visible is never culled (the images agree
// except for pixels where two surfaces tie in depth); history never hides what just came into
// view; a cold streaming cache is not waited for.

#include "TestDir.h"

#include <ff/builder/Generators.h>
#include <ff/builder/SceneBuilder.h>
#include <ff/runtime/CameraOptions.h>
#include <ff/runtime/OffscreenContext.h>
#include <ff/runtime/StreamingSession.h>
#include <ff/storage/SceneFile.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace ff::runtime {
namespace {

namespace fs = std::filesystem;

/** Pixels where surfaces tie in depth may differ with draw order: 0.01 % beyond those. */
constexpr double kTiedPixelShare = 1e-4;

using test::freshDir;

std::size_t differingPixels(const Image& a, const Image& b) {
    EXPECT_EQ(a.width, b.width);
    EXPECT_EQ(a.height, b.height);
    std::size_t differing = 0;
    for (std::size_t i = 0; i + 3 < a.rgba.size() && i + 3 < b.rgba.size(); i += 4)
        if (a.rgba[i] != b.rgba[i] || a.rgba[i + 1] != b.rgba[i + 1] ||
            a.rgba[i + 2] != b.rgba[i + 2] || a.rgba[i + 3] != b.rgba[i + 3])
            ++differing;
    return differing;
}

std::size_t allowedPixels(const Image& image) {
    return static_cast<std::size_t>(kTiedPixelShare * image.width * image.height);
}

/** The surface of the box [lo, hi], each face an n x n grid of quads (12 n² triangles). */
std::vector<storage::PackedTriangle> boxSurface(const glm::vec3& lo, const glm::vec3& hi, int n) {
    std::vector<storage::PackedTriangle> triangles;
    builder::SourceVertex v[4];
    for (int axis = 0; axis < 3; ++axis) {
        for (int side = 0; side < 2; ++side) {
            const int u = (axis + 1) % 3;
            const int w = (axis + 2) % 3;
            for (int i = 0; i < n; ++i) {
                for (int j = 0; j < n; ++j) {
                    for (int k = 0; k < 4; ++k) {
                        const int di = (k == 1 || k == 2) ? 1 : 0;
                        const int dj = (k >= 2) ? 1 : 0;
                        glm::vec3 p;
                        p[axis] = side ? hi[axis] : lo[axis];
                        p[u] = lo[u] +
                               (hi[u] - lo[u]) * static_cast<float>(i + di) / static_cast<float>(n);
                        p[w] = lo[w] +
                               (hi[w] - lo[w]) * static_cast<float>(j + dj) / static_cast<float>(n);
                        v[k].position = p;
                        v[k].color =
                                glm::vec4(0.3f + 0.2f * static_cast<float>(axis), 0.6f, 0.4f, 1.0f);
                    }
                    triangles.push_back(builder::packTriangle(v[0], v[1], v[2]));
                    triangles.push_back(builder::packTriangle(v[0], v[2], v[3]));
                }
            }
        }
    }
    return triangles;
}

constexpr int kStatueSubdivision = 8; // 768 triangles: worth a test
constexpr std::uint64_t kWallTriangles = 12;
constexpr std::uint64_t kStatueTriangles = 12 * kStatueSubdivision * kStatueSubdivision;

/** Format 1, for the tests that measured it until they are ported to format 2 (issue 16:
 *  version 1 is to be refused). */
builder::BuildOptions formatOne() {
    builder::BuildOptions options;
    options.formatVersion = storage::kFormatVersion;
    return options;
}

/** Builds `file` with what `fill` adds, within the smallest memory budget. */
template <typename Fill>
fs::path buildScene(const fs::path& file, Fill&& fill, builder::BuildOptions options = {}) {
    options.memoryBudgetBytes = builder::SceneBuilder::kMinimumBudgetBytes;
    auto scene = builder::SceneBuilder::create(file, options);
    EXPECT_TRUE(scene.isOk()) << scene.status().toString();
    if (!scene)
        return file;
    fill(**scene);
    auto report = (*scene)->finish();
    EXPECT_TRUE(report.isOk()) << report.status().toString();
    return file;
}

/** A statue, the box [-half, half]³ with faces of n x n quads, placed at z = -4. */
void addStatueBehind(builder::SceneBuilder& scene, float half, int n) {
    auto statue = scene.addPrototype("statue");
    EXPECT_TRUE(
            scene.addTriangles(*statue, boxSurface(glm::vec3(-half), glm::vec3(half), n)).isOk());
    glm::dmat4 behind(1.0);
    behind[3] = glm::dvec4(0.0, 0.0, -4.0, 1.0);
    EXPECT_TRUE(scene.addInstance(*statue, behind).isOk());
}

/** A 10 x 10 wall at z = 0 and, behind it (z = -4), a statue 2 units wide. */
fs::path buildWallAndStatue(const fs::path& dir, builder::BuildOptions options = {}) {
    return buildScene(
            dir / "wall.ffs",
            [](builder::SceneBuilder& scene) {
                auto wall = scene.addPrototype("wall");
                EXPECT_TRUE(
                        scene.addTriangles(*wall, boxSurface({-5, -5, -0.1f}, {5, 5, 0.1f}, 1)).isOk());
                EXPECT_TRUE(scene.addInstance(*wall, glm::dmat4(1.0)).isOk());
                addStatueBehind(scene, 1.0f, kStatueSubdivision);
            },
            options);
}

/** The wall as 10 x 10 tiles (instances of one 1 x 1 slab), and behind it a statue 4 wide
 *  (12 k triangles: enough below it at a coarse ε to be worth a test). */
fs::path buildTiledWallAndStatue(const fs::path& dir) {
    return buildScene(dir / "tiles.ffs", [](builder::SceneBuilder& scene) {
        auto tile = scene.addPrototype("tile");
        EXPECT_TRUE(
                scene.addTriangles(*tile, boxSurface({-0.5f, -0.5f, -0.1f}, {0.5f, 0.5f, 0.1f}, 1))
                        .isOk());
        for (int x = 0; x < 10; ++x) {
            for (int y = 0; y < 10; ++y) {
                glm::dmat4 at(1.0);
                at[3] = glm::dvec4(x - 4.5, y - 4.5, 0.0, 1.0);
                EXPECT_TRUE(scene.addInstance(*tile, at).isOk());
            }
        }
        addStatueBehind(scene, 2.0f, 4 * kStatueSubdivision);
    });
}

fs::path buildGenerated(
        const fs::path& dir, const std::string& generator, builder::BuildOptions options = {}) {
    return buildScene(
            dir / "scene.ffs",
            [&](builder::SceneBuilder& scene) {
                auto spec = builder::parseGeneratorSpec(generator);
                EXPECT_TRUE(spec.isOk());
                if (spec) {
                    EXPECT_TRUE(builder::runGenerator(*spec, scene).isOk());
                }
            },
            options);
}

class OcclusionCullingTest : public ::testing::Test {
protected:
    void SetUp() override {
        auto context = OffscreenContext::create();
        ASSERT_TRUE(context.isOk()) << context.status().toString();
        mContext = std::move(*context);
    }

    /** A session per mode, so neither sees the other's history or GPU pages. */
    void open(const fs::path& file, std::uint64_t cacheBytes = 0) {
        SessionOptions options;
        options.cacheBytes = cacheBytes;
        auto culling = StreamingSession::open(file, options);
        ASSERT_TRUE(culling.isOk()) << culling.status().toString();
        auto plain = StreamingSession::open(file, options);
        ASSERT_TRUE(plain.isOk()) << plain.status().toString();
        auto orderOnly = StreamingSession::open(file, options);
        ASSERT_TRUE(orderOnly.isOk()) << orderOnly.status().toString();
        mCulling = std::move(*culling);
        mPlain = std::move(*plain);
        mOrderOnly = std::move(*orderOnly);
        mBounds = sceneBounds(mCulling->scene());
    }

    FrameContext frame(const Camera& camera, float epsilon, bool occlusion) const {
        FrameContext context;
        context.camera = camera;
        context.camera.fitClipPlanes(mBounds);
        context.selection.epsilonPixels = epsilon;
        context.occlusion.enabled = occlusion;
        context.occlusion.backend = mBackend;
        return context;
    }

    /** Along walkWithJumps over the open scene (built from `generator`): culled frames show
     *  what the frustum-culled ones show, and occlusion culls something. */
    void expectNothingVisibleCulled(const std::string& generator, float epsilon);

    OcclusionBackend mBackend = OcclusionBackend::Queries;

    std::unique_ptr<OffscreenContext> mContext;
    std::unique_ptr<StreamingSession> mCulling;
    std::unique_ptr<StreamingSession> mPlain;
    std::unique_ptr<StreamingSession> mOrderOnly; ///< occlusion's order, every answer visible
    Bounds mBounds;
};

class BothBackends : public OcclusionCullingTest,
                     public ::testing::WithParamInterface<OcclusionBackend> {
protected:
    void SetUp() override {
        OcclusionCullingTest::SetUp();
        mBackend = GetParam();
    }
};

TEST_P(BothBackends, WhatIsBehindAWallNeverReachesGl) {
    open(buildWallAndStatue(freshDir()));
    const Camera front = Camera::lookAt({0, 0, 12}, {0, 0, 0}, {0, 1, 0}, 0.8f);
    auto reference = mPlain->render(frame(front, 1.0f, false));
    ASSERT_TRUE(reference.isOk()) << reference.status().toString();
    ASSERT_EQ(reference->stats.trianglesDrawn, kWallTriangles + kStatueTriangles);
    // The cold frame (no history) and the warm one both cull the statue.
    for (int f = 0; f < 3; ++f) {
        auto culled = mCulling->render(frame(front, 1.0f, true));
        ASSERT_TRUE(culled.isOk()) << culled.status().toString();
        SCOPED_TRACE("frame " + std::to_string(f));
        EXPECT_EQ(culled->stats.trianglesDrawn, kWallTriangles);
        EXPECT_GE(culled->stats.nodesOccluded, 1u);
        EXPECT_GE(culled->stats.occlusionQueries, 1u);
        EXPECT_EQ(culled->stats.cubesDrawn, 0u);
        EXPECT_LE(differingPixels(culled->image, reference->image), allowedPixels(culled->image));
    }
}

/** Two layers of statues (each the box [-0.5, 0.5]³ with faces of n x n quads), 6 x 6 side by
 *  side at z = 0 and the same 3 units behind: the front layer hides the back one whole from the
 *  +z axis, yet no box of one layer overlaps a box of the other. */
constexpr int kLayerSide = 6;
fs::path buildTwoLayersOfStatues(const fs::path& dir) {
    return buildScene(dir / "layers.ffs", [](builder::SceneBuilder& scene) {
        auto statue = scene.addPrototype("statue");
        EXPECT_TRUE(scene.addTriangles(*statue, boxSurface(glm::vec3(-0.5f), glm::vec3(0.5f), kStatueSubdivision))
                            .isOk());
        for (const double z : {0.0, -3.0}) {
            for (int x = 0; x < kLayerSide; ++x) {
                for (int y = 0; y < kLayerSide; ++y) {
                    glm::dmat4 at(1.0);
                    at[3] = glm::dvec4(x - 0.5 * (kLayerSide - 1), y - 0.5 * (kLayerSide - 1), z, 1.0);
                    EXPECT_TRUE(scene.addInstance(*statue, at).isOk());
                }
            }
        }
    });
}

TEST_P(BothBackends, AFrameWithoutHistoryTestsWhatIsBehindOnlyOnceWhatIsInFrontIsDrawn) {
    // The first frame has no history: every statue is tested. At ε = 0 a node is tested by its
    // tight bounds, which overlap nothing of the other layer. Tested in the same batch as the
    // front layer, the back layer would see none of it drawn yet and be drawn too; a node whose
    // box lies behind a nearer one waiting for its answer, on screen, waits for it instead.
    open(buildTwoLayersOfStatues(freshDir()));
    const Camera front = Camera::lookAt({0, 0, 12}, {0, 0, 0}, {0, 1, 0}, 0.8f);
    auto reference = mPlain->render(frame(front, 0.0f, false));
    ASSERT_TRUE(reference.isOk()) << reference.status().toString();
    constexpr std::uint64_t kLayer = kLayerSide * kLayerSide * kStatueTriangles;
    ASSERT_EQ(reference->stats.trianglesDrawn, 2 * kLayer);
    auto culled = mCulling->render(frame(front, 0.0f, true));
    ASSERT_TRUE(culled.isOk()) << culled.status().toString();
    EXPECT_EQ(culled->stats.trianglesDrawn, kLayer);
    EXPECT_GE(culled->stats.nodesOccluded, 1u);
    EXPECT_LE(differingPixels(culled->image, reference->image), allowedPixels(culled->image));
}

TEST_P(BothBackends, AFrameWithoutHistoryStopsTestingWhereNothingDrawnToDepthIsHidden) {
    // 4,096 trees from five radii at ε = 1: every tree is far enough to be drawn as cubes
    // (points), which write no depth, over a ground that hides none of them. Without history
    // each group of trees is worth a test (1,346 tests before this rule); once the
    // frame's answers keep finding everything visible while nothing new is drawn to depth,
    // the groups left are drawn untested (OcclusionTraversal.cpp, kPriorHiddenShare).
    open(buildGenerated(freshDir(), "forest:trees=4096", formatOne()));
    const Camera camera = Camera::orbit(mBounds, 5.0f, 30.0f, 20.0f, 0.8f);
    auto reference = mPlain->render(frame(camera, 1.0f, false));
    ASSERT_TRUE(reference.isOk()) << reference.status().toString();
    auto culled = mCulling->render(frame(camera, 1.0f, true));
    ASSERT_TRUE(culled.isOk()) << culled.status().toString();
    ASSERT_EQ(culled->stats.nodesOccluded, 0u);
    ASSERT_LE(culled->stats.trianglesDrawn, 64u); // the ground, nothing to occlude with
    EXPECT_EQ(culled->stats.instancesEntered, 4096u);
    EXPECT_GE(culled->stats.occlusionQueries, 1u);
    EXPECT_LE(culled->stats.occlusionQueries * 8, culled->stats.instancesEntered);
    EXPECT_EQ(culled->stats.cubesDrawn, reference->stats.cubesDrawn);
    EXPECT_LE(differingPixels(culled->image, reference->image), allowedPixels(culled->image));
}

TEST_P(BothBackends, WhatATestHidIsCountedInTriangles) {
    // Format 2's records carry their subtree's triangle count: the statue's are counted as
    // occluded, and nothing else. (Format 1's records carry none: nothing is counted there.)
    builder::BuildOptions options;
    options.formatVersion = storage::kFormatVersion2;
    open(buildWallAndStatue(freshDir(), options));
    const Camera front = Camera::lookAt({0, 0, 12}, {0, 0, 0}, {0, 1, 0}, 0.8f);
    for (int f = 0; f < 2; ++f) {
        SCOPED_TRACE("frame " + std::to_string(f));
        auto culled = mCulling->render(frame(front, 1.0f, true));
        ASSERT_TRUE(culled.isOk()) << culled.status().toString();
        EXPECT_EQ(culled->stats.trianglesDrawn, kWallTriangles);
        EXPECT_GE(culled->stats.nodesOccluded, 1u);
        EXPECT_EQ(culled->stats.trianglesOccluded, kStatueTriangles);
    }
    auto plain = mPlain->render(frame(front, 1.0f, false));
    ASSERT_TRUE(plain.isOk()) << plain.status().toString();
    EXPECT_EQ(plain->stats.trianglesOccluded, 0u);
}

TEST_P(BothBackends, OpaqueCubesOcclude) {
    // At ε = 64 each tile (about 47 pixels wide) is drawn as its color cube, whose face toward
    // the eye is covered whole (alpha 1); the statue behind is too large to be one.
    open(buildTiledWallAndStatue(freshDir()));
    const Camera front = Camera::lookAt({0, 0, 12}, {0, 0, 0}, {0, 1, 0}, 0.8f);
    constexpr float kEpsilon = 64.0f;
    auto reference = mPlain->render(frame(front, kEpsilon, false));
    ASSERT_TRUE(reference.isOk()) << reference.status().toString();
    ASSERT_GT(reference->stats.trianglesDrawn + reference->stats.cubesDrawn, 100u);
    // At this ε the statue's subtree is a few dozen cubes: tested all the same.
    FrameContext with = frame(front, kEpsilon, true);
    with.occlusion.minTestTriangles = 16;
    FrameContext without = with;
    without.occlusion.cubesOcclude = false;
    auto seenThrough = mOrderOnly->render(without);
    ASSERT_TRUE(seenThrough.isOk()) << seenThrough.status().toString();
    EXPECT_EQ(seenThrough->stats.nodesOccluded, 0u); // cubes write no depth: nothing hides it
    for (int f = 0; f < 3; ++f) {
        SCOPED_TRACE("frame " + std::to_string(f));
        auto culled = mCulling->render(with);
        ASSERT_TRUE(culled.isOk()) << culled.status().toString();
        EXPECT_GE(culled->stats.occluderCubes, 1u);
        EXPECT_GE(culled->stats.nodesOccluded, 1u);
        EXPECT_LT(
                culled->stats.trianglesDrawn + culled->stats.cubesDrawn,
                seenThrough->stats.trianglesDrawn + seenThrough->stats.cubesDrawn);
        EXPECT_LE(differingPixels(culled->image, reference->image), allowedPixels(culled->image));
    }
}

TEST_F(OcclusionCullingTest, TheOracleDrawsExactlyWhatShows) {
    open(buildWallAndStatue(freshDir(), formatOne()));
    const Camera front = Camera::lookAt({0, 0, 12}, {0, 0, 0}, {0, 1, 0}, 0.8f);
    auto reference = mPlain->render(frame(front, 1.0f, false));
    ASSERT_TRUE(reference.isOk());
    auto oracle = mPlain->renderOracle(frame(front, 1.0f, false));
    ASSERT_TRUE(oracle.isOk()) << oracle.status().toString();
    // The wall's face toward the eye (its two triangles, and edge-on sides where they tie at
    // the silhouette), none of the statue.
    EXPECT_EQ(reference->stats.trianglesDrawn, kWallTriangles + kStatueTriangles);
    EXPECT_GE(oracle->stats.trianglesDrawn, 2u);
    EXPECT_LT(oracle->stats.trianglesDrawn, kWallTriangles);
    // What it left out is what it counts as occluded: the statue and the wall's hidden faces.
    EXPECT_EQ(oracle->stats.trianglesDrawn + oracle->stats.trianglesOccluded, reference->stats.trianglesDrawn);
    EXPECT_EQ(differingPixels(oracle->image, reference->image), 0u);
}

TEST_F(OcclusionCullingTest, TheOracleDropsCubesBehindOpaqueGeometry) {
    // At ε = 64 the statue (about 60 pixels wide) is drawn as cubes, the wall as its triangles:
    // cubes write no depth, but the wall's hides them all.
    open(buildWallAndStatue(freshDir(), formatOne()));
    const Camera front = Camera::lookAt({0, 0, 12}, {0, 0, 0}, {0, 1, 0}, 0.8f);
    auto reference = mPlain->render(frame(front, 64.0f, false));
    ASSERT_TRUE(reference.isOk());
    ASSERT_GE(reference->stats.cubesDrawn, 1u);
    // Also in batches of one draw each: a frame that spills over one batch draws its cubes in a
    // second walk, which counts them nowhere (its geometry walk did).
    for (const std::size_t batchBytes : {FrameBudgets{}.drawBatchBytes, std::size_t{1}}) {
        SCOPED_TRACE("batches of " + std::to_string(batchBytes) + " bytes");
        FrameContext context = frame(front, 64.0f, false);
        context.budgets.drawBatchBytes = batchBytes;
        auto oracle = mPlain->renderOracle(context);
        ASSERT_TRUE(oracle.isOk()) << oracle.status().toString();
        EXPECT_EQ(oracle->stats.cubesDrawn, 0u);
        EXPECT_EQ(oracle->stats.cubeFacesDrawn, 0u);
        EXPECT_GE(oracle->stats.trianglesDrawn, 2u);
        EXPECT_EQ(differingPixels(oracle->image, reference->image), 0u);
    }
    // From the side the statue's cubes show, and the oracle keeps them.
    const Camera side = Camera::lookAt({14, 0, -4}, {0, 0, -4}, {0, 1, 0}, 0.8f);
    auto seen = mPlain->renderOracle(frame(side, 64.0f, false));
    ASSERT_TRUE(seen.isOk()) << seen.status().toString();
    auto seenReference = mPlain->render(frame(side, 64.0f, false));
    ASSERT_TRUE(seenReference.isOk());
    EXPECT_GE(seen->stats.cubesDrawn, 1u);
    EXPECT_EQ(differingPixels(seen->image, seenReference->image), 0u);
}

TEST_P(BothBackends, HistoryNeverHidesWhatJustCameIntoView) {
    open(buildWallAndStatue(freshDir()));
    const Camera front = Camera::lookAt({0, 0, 12}, {0, 0, 0}, {0, 1, 0}, 0.8f);
    // From the side, past the wall's edge: the statue is in plain view.
    const Camera side = Camera::lookAt({14, 0, -4}, {0, 0, -4}, {0, 1, 0}, 0.8f);
    for (int f = 0; f < 3; ++f)
        ASSERT_TRUE(mCulling->render(frame(front, 1.0f, true)).isOk());
    auto culled = mCulling->render(frame(side, 1.0f, true));
    ASSERT_TRUE(culled.isOk()) << culled.status().toString();
    auto reference = mPlain->render(frame(side, 1.0f, false));
    ASSERT_TRUE(reference.isOk());
    EXPECT_EQ(culled->stats.trianglesDrawn, reference->stats.trianglesDrawn);
    EXPECT_EQ(culled->stats.trianglesDrawn, kWallTriangles + kStatueTriangles);
    EXPECT_LE(differingPixels(culled->image, reference->image), allowedPixels(culled->image));
}

TEST_P(BothBackends, FramesGoUntestedWhereCullingDoesNotPayUntilTheCameraJumps) {
    // With --occlusion-min-hidden 0.05, from the side, where nothing is hidden: the first
    // frame's tests hide nothing, so the next frames are drawn as frustum culling draws them,
    // without tests, then one is tested again; a jump to where the wall hides the statue is
    // tested at once.
    open(buildWallAndStatue(freshDir()));
    const Camera side = Camera::lookAt({14, 0, -4}, {0, 0, -4}, {0, 1, 0}, 0.8f);
    const Camera front = Camera::lookAt({0, 0, 12}, {0, 0, 0}, {0, 1, 0}, 0.8f);
    auto reference = mPlain->render(frame(side, 1.0f, false));
    ASSERT_TRUE(reference.isOk()) << reference.status().toString();
    const auto skipping = [&](const Camera& camera) {
        FrameContext context = frame(camera, 1.0f, true);
        context.occlusion.minHiddenShare = 0.05f;
        return context;
    };
    std::vector<int> untested;
    for (int f = 0; f < 12; ++f) {
        SCOPED_TRACE("frame " + std::to_string(f));
        auto culled = mCulling->render(skipping(side));
        ASSERT_TRUE(culled.isOk()) << culled.status().toString();
        EXPECT_EQ(culled->stats.nodesOccluded, 0u);
        EXPECT_EQ(culled->stats.trianglesDrawn, reference->stats.trianglesDrawn);
        if (culled->stats.occlusionSkipped == 0) {
            EXPECT_GE(culled->stats.occlusionQueries, 1u);
            EXPECT_LE(differingPixels(culled->image, reference->image), allowedPixels(culled->image));
            continue;
        }
        untested.push_back(f);
        EXPECT_EQ(culled->stats.occlusionQueries, 0u);
        EXPECT_EQ(differingPixels(culled->image, reference->image), 0u) << "frustum culling's frame";
    }
    EXPECT_EQ(untested, (std::vector<int>{1, 2, 3, 4, 5, 6, 7, 8, 10, 11}));

    auto jumped = mCulling->render(skipping(front));
    ASSERT_TRUE(jumped.isOk()) << jumped.status().toString();
    EXPECT_EQ(jumped->stats.occlusionSkipped, 0u);
    EXPECT_EQ(jumped->stats.trianglesDrawn, kWallTriangles);

    // By default every frame is tested, also where frames went untested before.
    for (int f = 0; f < 2; ++f)
        ASSERT_TRUE(mCulling->render(skipping(side)).isOk());
    for (int f = 0; f < 3; ++f) {
        SCOPED_TRACE("every frame " + std::to_string(f));
        auto culled = mCulling->render(frame(side, 1.0f, true));
        ASSERT_TRUE(culled.isOk()) << culled.status().toString();
        EXPECT_EQ(culled->stats.occlusionSkipped, 0u);
    }
}

/** A walk with jumps: orbit steps, a teleport to the far side, a view from inside, and back. */
std::vector<Camera> walkWithJumps(const Bounds& bounds) {
    std::vector<Camera> cameras;
    for (float azimuth : {0.0f, 6.0f, 12.0f, 190.0f, 196.0f})
        cameras.push_back(Camera::orbit(bounds, 2.2f, azimuth, 20.0f, 0.8f));
    cameras.push_back(Camera::orbit(bounds, 0.3f, 40.0f, 10.0f, 0.8f)); // inside
    cameras.push_back(Camera::orbit(bounds, 1.4f, 80.0f, 50.0f, 0.8f));
    cameras.push_back(Camera::orbit(bounds, 2.2f, 0.0f, 20.0f, 0.8f));
    return cameras;
}

class NothingVisibleIsCulled
    : public OcclusionCullingTest,
      public ::testing::WithParamInterface<std::tuple<std::string, float, OcclusionBackend>> {};

TEST_P(NothingVisibleIsCulled, AlongAWalkWithJumps) {
    const auto& [generator, epsilon, backend] = GetParam();
    mBackend = backend;
    open(buildGenerated(freshDir(), generator));
    expectNothingVisibleCulled(generator, epsilon);
}

void OcclusionCullingTest::expectNothingVisibleCulled(
        const std::string& generator, float epsilon) {
    std::uint64_t occluded = 0;
    std::size_t mostTies = 0;
    std::uint64_t culledTriangles = 0;
    std::uint64_t plainTriangles = 0;
    const std::vector<Camera> walk = walkWithJumps(mBounds);
    for (std::size_t i = 0; i < walk.size(); ++i) {
        SCOPED_TRACE("camera " + std::to_string(i));
        auto culled = mCulling->render(frame(walk[i], epsilon, true));
        ASSERT_TRUE(culled.isOk()) << culled.status().toString();
        auto reference = mPlain->render(frame(walk[i], epsilon, false));
        ASSERT_TRUE(reference.isOk()) << reference.status().toString();
        // The oracle keeps exactly the triangles and cubes of the frustum-culled frame that show
        // a sample; culling by nodes may draw more, never fewer (a count check beside the image
        // check below: a culled node that held one of them would draw fewer).
        auto shows = mPlain->renderOracle(frame(walk[i], epsilon, false));
        ASSERT_TRUE(shows.isOk()) << shows.status().toString();
        EXPECT_GE(culled->stats.trianglesDrawn, shows->stats.trianglesDrawn);
        EXPECT_GE(culled->stats.cubesDrawn, shows->stats.cubesDrawn);
        // Where surfaces tie in depth (the forest's crossed leaves), draw order decides: the
        // same walk with every answer taken as visible draws in culling's order without
        // culling, and counts those pixels.
        FrameContext orderOnly = frame(walk[i], epsilon, true);
        orderOnly.occlusion.ignoreAnswers = true;
        auto unculled = mOrderOnly->render(orderOnly);
        ASSERT_TRUE(unculled.isOk()) << unculled.status().toString();
        const std::size_t ties = differingPixels(unculled->image, reference->image);
        // The forest's leaves cross and coincide, so its ties run higher than the molecule's
        // (up to 451 pixels, 0.15 %, in a forest of 64 trees, from inside it on the cold frame
        // after the jump there, where nodes held back behind unanswered ones are drawn later
        // than their distance; none in the 16 trees of this walk, measured 2026-12-08).
        const double tieShare = generator.starts_with("forest") ? 2e-3 : kTiedPixelShare;
        EXPECT_LE(
                static_cast<double>(ties),
                tieShare * unculled->image.width * unculled->image.height)
                << "depth ties";
        mostTies = std::max(mostTies, ties);
        EXPECT_LE(
                differingPixels(culled->image, reference->image),
                ties + allowedPixels(culled->image));
        EXPECT_LE(culled->stats.trianglesDrawn, reference->stats.trianglesDrawn);
        occluded += culled->stats.nodesOccluded;
        culledTriangles += culled->stats.trianglesDrawn;
        plainTriangles += reference->stats.trianglesDrawn;
    }
    RecordProperty("most_tied_pixels", std::to_string(mostTies));
    // The comparison above means something only if occlusion culled something.
    EXPECT_GT(occluded, 0u);
    EXPECT_LT(culledTriangles, plainTriangles);
}

std::string
sceneName(const ::testing::TestParamInfo<std::tuple<std::string, float, OcclusionBackend>>& param) {
    const auto& [generator, epsilon, backend] = param.param;
    return generator.substr(0, generator.find(':')) + (epsilon == 0.0f ? "_eps0" : "_eps1") + "_" +
           occlusionBackendName(backend);
}

// A forest of 16 trees (4 x 4): trees hide trees along the walk as in one of 64, and drawn as
// format 2 (its leaves of 16 triangles as clusters) a walk of 64 took 4-9 minutes under the
// sanitizers, 1.5 x format 1's.
INSTANTIATE_TEST_SUITE_P(
        Scenes,
        NothingVisibleIsCulled,
        ::testing::Combine(
                ::testing::Values("molecule:spheres=2000", "forest:trees=16"),
                ::testing::Values(0.0f, 1.0f),
                ::testing::Values(OcclusionBackend::Queries)),
        sceneName);

// The depth pyramid where it culls. Not the forest at ε = 1: its occluders are leaves with sky
// between them, so every 4x4 block of the pyramid holds the background's depth and nothing is
// culled (a max-depth test's known weakness; the queries cull there).
INSTANTIATE_TEST_SUITE_P(
        PyramidScenes,
        NothingVisibleIsCulled,
        ::testing::Values(
                std::tuple<std::string, float, OcclusionBackend>{
                        "molecule:spheres=2000", 0.0f, OcclusionBackend::Hzb},
                std::tuple<std::string, float, OcclusionBackend>{
                        "molecule:spheres=2000", 1.0f, OcclusionBackend::Hzb},
                std::tuple<std::string, float, OcclusionBackend>{
                        "forest:trees=16", 0.0f, OcclusionBackend::Hzb}),
        sceneName);

/** Format 2 (48-byte records, bounds quantized outward, clusters) with each decomposition of
 *  the hierarchy: what occlusion culling needs of a hierarchy survives the format. */
class FormatTwoDecompositions
    : public OcclusionCullingTest,
      public ::testing::WithParamInterface<std::tuple<builder::Decomposition, float>> {};

TEST_P(FormatTwoDecompositions, NothingVisibleIsCulledAlongAWalkWithJumps) {
    const auto& [decomposition, epsilon] = GetParam();
    builder::BuildOptions options;
    options.formatVersion = storage::kFormatVersion2;
    options.hierarchy.decomposition = decomposition;
    const std::string generator = "molecule:spheres=300";
    open(buildGenerated(freshDir(), generator, options));
    ASSERT_EQ(mCulling->scene().formatVersion(), storage::kFormatVersion2);
    expectNothingVisibleCulled(generator, epsilon);
}

// Both ε on the octree; the others at ε = 1, where both cubes and triangles are drawn (each
// case takes ~30 s under the sanitizers).
INSTANTIATE_TEST_SUITE_P(
        Decompositions,
        FormatTwoDecompositions,
        ::testing::Values(
                std::tuple{builder::Decomposition::Octree, 0.0f},
                std::tuple{builder::Decomposition::Octree, 1.0f},
                std::tuple{builder::Decomposition::Dbvd, 1.0f},
                std::tuple{builder::Decomposition::Phbvo, 1.0f},
                std::tuple{builder::Decomposition::Balanced, 1.0f}),
        [](const auto& param) {
            return std::string(builder::decompositionName(std::get<0>(param.param))) +
                   (std::get<1>(param.param) == 0.0f ? "_eps0" : "_eps1");
        });

// A format 2 file is drawn through a cache that waits for every page a frame lacks, drawing the
// frame again until it is complete: the passes without their pages find nodes visible that are
// not, and with coherence those would be drawn untested for frames after (the city's walk drew
// 14 x format 1's triangles in its first 30 frames). Only the complete pass's answers may stay.
// Pass 1 walks what is too small to test whole and hands the cubes it met there to pass 2,
// which draws them without walking there again (BackToFrontTraversal's met cubes): with every
// answer taken as visible, the same cubes as the frustum-culled frame's, counted alike and
// blended in the same order. From 2.2 radii the trees' inner cells are walked whole, from 5
// whole trees (their cubes met in the instance's frame). With batches of 16 KiB the record
// (bounded like a batch) fills after a few hundred cubes and pass 2 walks the rest itself.
TEST_F(OcclusionCullingTest, CubesMetInSubtreesWalkedWholeBlendAsWithoutOcclusion) {
    open(buildGenerated(freshDir(), "forest:trees=64"));
    for (const std::size_t batchBytes : {FrameBudgets{}.drawBatchBytes, std::size_t{16} << 10}) {
        for (const float distance : {2.2f, 5.0f}) {
            SCOPED_TRACE(
                    "distance " + std::to_string(distance) + ", batches of " +
                    std::to_string(batchBytes));
            const Camera camera = Camera::orbit(mBounds, distance, 30.0f, 20.0f, 0.8f);
            FrameContext orderOnly = frame(camera, 1.0f, true);
            orderOnly.occlusion.ignoreAnswers = true;
            orderOnly.budgets.drawBatchBytes = batchBytes;
            auto unculled = mOrderOnly->render(orderOnly);
            ASSERT_TRUE(unculled.isOk()) << unculled.status().toString();
            FrameContext plain = frame(camera, 1.0f, false);
            plain.budgets.drawBatchBytes = batchBytes;
            auto reference = mPlain->render(plain);
            ASSERT_TRUE(reference.isOk()) << reference.status().toString();
            EXPECT_GT(reference->stats.cubesDrawn, 1000u);
            EXPECT_EQ(unculled->stats.cubesDrawn, reference->stats.cubesDrawn);
            EXPECT_EQ(unculled->stats.cubeFacesDrawn, reference->stats.cubeFacesDrawn);
            EXPECT_EQ(unculled->stats.cubeFacesPerLevel, reference->stats.cubeFacesPerLevel);
            EXPECT_EQ(unculled->stats.trianglesDrawn, reference->stats.trianglesDrawn);
            // Only the geometry's order differs (front to back): the forest's crossed leaves
            // tie in depth (NothingVisibleIsCulled's bound); cubes blended out of order differ
            // far more.
            EXPECT_LE(
                    static_cast<double>(differingPixels(unculled->image, reference->image)),
                    2e-3 * unculled->image.width * unculled->image.height);
        }
    }
}

TEST_F(OcclusionCullingTest, ACompleteFrameRemembersOnlyItsLastPass) {
    builder::BuildOptions options;
    options.formatVersion = storage::kFormatVersion2;
    open(buildGenerated(freshDir(), "city:blocks=4", options));
    const std::vector<Camera> walk = walkWithJumps(mBounds);
    FrameContext coherent = frame(walk[0], 0.0f, true);
    FrameContext testsEveryNode = coherent;
    testsEveryNode.occlusion.coherent = false;
    std::uint64_t firstFrame = 0;
    for (int f = 0; f < 3; ++f) {
        SCOPED_TRACE("frame " + std::to_string(f));
        auto withHistory = mCulling->render(coherent);
        ASSERT_TRUE(withHistory.isOk()) << withHistory.status().toString();
        auto without = mOrderOnly->render(testsEveryNode);
        ASSERT_TRUE(without.isOk()) << without.status().toString();
        if (f == 0)
            firstFrame = without->stats.trianglesDrawn;
        // A still camera: the history holds what the complete first frame found visible, so
        // coherence draws what that frame drew (before the fix: 104,660 triangles against
        // 4,448). Not what testing every node draws on the frames after: without history the
        // walk holds more nodes back, in another order (OcclusionTraversal.cpp,
        // kHeldBehindWaits), and its answers differ (here 5,144 triangles against 4,448).
        EXPECT_LE(
                static_cast<double>(withHistory->stats.trianglesDrawn),
                1.1 * static_cast<double>(firstFrame));
        EXPECT_EQ(differingPixels(withHistory->image, without->image), 0u);
    }
}

TEST_P(BothBackends, AColdCacheIsNotWaitedFor) {
    open(buildGenerated(freshDir(), "molecule:spheres=2000"), 64ull << 20);
    const Camera camera = Camera::orbit(mBounds, 2.2f, 0.0f, 20.0f, 0.8f);
    // The first frame has only the root page: it draws what it has, without waiting.
    auto first = mCulling->render(frame(camera, 1.0f, true));
    ASSERT_TRUE(first.isOk()) << first.status().toString();
    EXPECT_GT(first->stats.pagesMissing, 0u);
    EXPECT_FALSE(mCulling->lastFrame().stalled);
    // Converged, it draws what the plain walk draws.
    auto culled = mCulling->renderComplete(frame(camera, 1.0f, true));
    ASSERT_TRUE(culled.isOk()) << culled.status().toString();
    auto reference = mPlain->renderComplete(frame(camera, 1.0f, false));
    ASSERT_TRUE(reference.isOk()) << reference.status().toString();
    EXPECT_LE(differingPixels(culled->image, reference->image), allowedPixels(culled->image));
    EXPECT_GT(culled->stats.nodesOccluded, 0u);
}

INSTANTIATE_TEST_SUITE_P(
        Backends,
        BothBackends,
        ::testing::Values(OcclusionBackend::Queries, OcclusionBackend::Hzb),
        [](const auto& param) { return std::string(occlusionBackendName(param.param)); });

} // namespace
} // namespace ff::runtime
