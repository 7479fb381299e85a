#pragma once

// Building scenes in tests and checking what comes out: every drawable triangle stored exactly
// once, in its prototype, reachable from the roots, inside its node's bounds; counts that match.

#include "RecordingSink.h"

#include <ff/builder/SceneBuilder.h>
#include <ff/storage/SceneFile.h>

#include <glm/glm.hpp>

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace ff::builder::testing {

/** A fresh, empty directory for the running test. */
std::filesystem::path freshTestDir();

/** The smallest budget and page: many pages, so node levels and runs cross page ends. */
BuildOptions smallOptions(unsigned threads = 1);

/** A generator's scene, recorded so that it can be fed to several builders. */
RecordingSink generate(const std::string& text);

/** Feeds a recorded scene into `sink` in batches, as a source would. */
Status replay(const RecordingSink& scene, ISceneSink& sink);

/** Builds `scene` into `output`; the Result of finish() (or of the step that failed). */
Result<BuildReport> buildScene(
        const RecordingSink& scene,
        const std::filesystem::path& output,
        const BuildOptions& options);

/** buildScene, failing the test on an error. */
BuildReport buildOrFail(
        const RecordingSink& scene,
        const std::filesystem::path& output,
        const BuildOptions& options);

SourceVertex vertexAt(const glm::vec3& p, const glm::vec3& color = glm::vec3(0.6f, 0.5f, 0.4f));

/** A small triangle with centroid `c` and edge `size`, in a plane tilted so every face sees it. */
storage::PackedTriangle triangleAt(const glm::vec3& c, float size);

/** Deterministic pseudo-random numbers in [0, 1). */
class Lcg {
public:
    explicit Lcg(std::uint64_t seed)
        : mState(seed) {}
    float next() {
        mState = mState * 6364136223846793005ull + 1442695040888963407ull;
        return static_cast<float>(mState >> 40) / static_cast<float>(1ull << 24);
    }
    glm::vec3 inBox(const glm::vec3& lo, const glm::vec3& hi) {
        const float x = next();
        const float y = next();
        const float z = next();
        return lo + (hi - lo) * glm::vec3(x, y, z);
    }

private:
    std::uint64_t mState;
};

/** `count` small triangles scattered through the box [lo, hi]. */
std::vector<storage::PackedTriangle>
cluster(std::size_t count, const glm::vec3& lo, const glm::vec3& hi, std::uint64_t seed);

/** One prototype with the given triangles and one identity instance. */
RecordingSink singlePrototypeScene(const std::vector<storage::PackedTriangle>& triangles);

/** What is reachable in a scene file, gathered by walking it from the roots. */
struct StoredScene {
    std::unique_ptr<storage::SceneFile> file;
    std::uint64_t nodes = 0;                  ///< distinct node records reached
    std::vector<std::uint32_t> instanceNodes; ///< instance index of every Instance node
    std::vector<std::vector<std::string>> prototypeTriangles; ///< sorted, per prototype
    std::vector<std::uint64_t> prototypeNodes;
    std::uint64_t storedTriangles = 0;
};

/** Opens `path`, verifies every page and walks the instance level and every prototype. */
void readScene(const std::filesystem::path& path, StoredScene& out);

/** The checks every built scene must pass against the scene that was fed in. */
void expectSceneMatches(
        const std::filesystem::path& path, const RecordingSink& scene, const BuildReport& report);

} // namespace ff::builder::testing
