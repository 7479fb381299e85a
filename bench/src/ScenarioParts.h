#pragma once

// Parts shared by the "views" and "path" scenario kinds: the scene (and how it is built), the
// methods compared, the full reference. Keys and meanings: bench/README.md.

#include "BenchSupport.h"

#include <ff/bench/Scenario.h>
#include <ff/runtime/CameraPathGenerators.h>
#include <ff/runtime/Selection.h>
#include <ff/storage/Status.h>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace ff::bench {

/** "scene" ({"gltf": FILE} or {"generate": SPEC}) and "build" (extra `farfield build` flags),
 *  with ${shared} expanded. */
struct SceneSpec {
    std::string gltf;                    ///< glTF input, or empty
    std::string generate;                ///< generator spec, or empty
    std::vector<std::string> buildFlags; ///< appended to `farfield build`
};

/** Reads "scene" and "build"; errors go to the reader. */
SceneSpec readSceneSpec(ScenarioReader& reader);

/** Reads "build" alone (flags every build of a generated ladder gets), ${shared} expanded. */
std::vector<std::string> readBuildFlags(ScenarioReader& reader);

/** " Every scene is built with `FLAGS`." for a report (nothing without flags). */
std::string buildFlagsNote(const std::vector<std::string>& flags);

/** Builds the scene into `output` with a child `farfield build -q` (so every flag means what
 *  it means on the command line), with `extraFlags` after the scenario's own; returns the
 *  child's time and peak RSS. */
[[nodiscard]] Result<ChildRun> buildScene(
        const SceneSpec& scene,
        const std::vector<std::string>& extraFlags,
        const std::filesystem::path& output,
        const std::string& selfExe);

/** "path": a camera path made by one of `farfield path`'s generators, fitted to the scene. */
struct PathSpec {
    std::string generator = "orbit"; ///< orbit, flythrough, teleports or walk (options.legs: world)
    runtime::PathGeneratorOptions options;

    /** `farfield path` arguments (after the executable) that write this path for `scene`. */
    std::vector<std::string> commandArgs(const std::filesystem::path& scene, const std::filesystem::path& output) const;
};

/** Reads "path" ({generator, frames, fps, seed, teleports, fov}) over `fallback`; frames must be
 *  at least `minFrames`. Errors go to the reader. */
PathSpec readPathSpec(ScenarioReader& reader, PathSpec fallback, std::int64_t minFrames);

/** The streaming cache's settings, as `farfield replay` takes them. */
struct CacheSpec {
    std::int64_t cacheMb = 512;
    std::int64_t ioThreads = 2;
    std::int64_t uploadsPerFrame = 64;
    std::int64_t prefetchFrames = 4;
};

/** Reads cache_mb (at least `minCacheMb`), io_threads, uploads_per_frame and prefetch_frames
 *  over `fallback`. Errors go to the reader. */
CacheSpec readCacheSpec(ScenarioReader& reader, CacheSpec fallback, std::int64_t minCacheMb);

/** One method compared: a label and the selection options its keys set. */
struct MethodSpec {
    std::string label;
    runtime::SelectionOptions selection;
    runtime::OcclusionOptions occlusion;
    /** Drawn by the occlusion oracle (StreamingSession::renderOracle): every page mapped. */
    bool oracle = false;
    /** Path scenarios: the scene built with `--decomposition` this (empty: as the scenario's
     *  "build" flags say); methods with the same one share a build. */
    std::string decomposition;

    bool isFull() const noexcept { return selection.method == runtime::Method::Full; }
    /** "full" / "hierarchical" */
    const char* methodName() const noexcept;
    /** "faces" / "points" / "auto" */
    const char* cubeDrawName() const noexcept;
};

/** Method keys a sweep may vary (the others, label and method, name what is swept). */
inline constexpr const char* kSweepableMethodKeys[] = {
        "eps",       "cube_draw",        "cube_anisotropy",   "representation", "splat_size", "splat_shape",
        "occlusion", "coherence",        "oracle",            "occlusion_backend", "cube_occluders", "opacity_threshold",
        "occlusion_min_hidden"};

/** Reads "methods" (a non-empty array; labels unique); errors go to the reader. */
std::vector<MethodSpec> readMethods(ScenarioReader& reader);

/** Sets one sweepable method key from a JSON value; InvalidArgument naming key and value. */
[[nodiscard]] Status
setMethodKey(MethodSpec& method, const std::string& key, const nlohmann::json& value);

/** A sweep value as text: 0.5 -> "0.5", "faces" -> "faces" (for CSV cells and build flags). */
std::string sweepValueText(const nlohmann::json& value);

/** "reference": {"supersample": N}, N in 1..16; the reference is always method full. */
int readReferenceSupersample(ScenarioReader& reader, int fallback);

} // namespace ff::bench
