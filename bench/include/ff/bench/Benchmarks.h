#pragma once

// The benchmark kinds a scenario file can name. Each kind reads and checks its scenario's keys
// up front (prepare*: errors name the file and the key, nothing has run yet) and returns how to
// run it; `farfield bench` prepares every scenario it was given before running the first.

#include <ff/bench/Scenario.h>

#include <ff/storage/Status.h>

#include <filesystem>
#include <functional>
#include <string>

namespace ff::bench {

struct BenchOptions {
    std::filesystem::path outDir = "docs/results";
    std::filesystem::path workDir; ///< scene files (large; default: outDir/scenes, removed after)
    int timedFrames = 3;           ///< timed frames per measurement (median), after one warm-up
    std::string selfExe;           ///< this executable, for child builds
    std::string command;           ///< the command line that reruns the scenario, for reports
};

/** A prepared scenario: runs it, writing OUT/NAME.csv, OUT/NAME*.png, OUT/NAME.md. */
using BenchRun = std::function<Status(const BenchOptions&)>;

/** Chamberlain et al. '96 Table 2 on the tree: full vs hierarchical at d = 1.75..14 radii. */
[[nodiscard]] Result<BenchRun> prepareTable2(const Scenario& scenario);
/** The recursively instanced forest, 1 to 16384 trees, at one fixed view (log-log chart). */
[[nodiscard]] Result<BenchRun> prepareForest(const Scenario& scenario);
/** Working set of a complete frame against scene size; cold-cache teleports on a terrain. */
[[nodiscard]] Result<BenchRun> preparePaging(const Scenario& scenario);
/** Builder throughput and peak RSS on terrain ladders. */
[[nodiscard]] Result<BenchRun> prepareBuild(const Scenario& scenario);
/** Speed against accuracy of methods at fixed views, optionally swept over a parameter. */
[[nodiscard]] Result<BenchRun> prepareViews(const Scenario& scenario);
/** Popping, flicker and paging along a generated camera path, per frame and per method. */
[[nodiscard]] Result<BenchRun> preparePath(const Scenario& scenario);

/** A scene built (time, peak RSS) and a camera path replayed through a cold cache of a given
 *  budget: per-frame telemetry and the replay summary (the larger-than-RAM benchmark). */
[[nodiscard]] Result<BenchRun> prepareReplay(const Scenario& scenario);

/** One complete frame per view by a child `farfield render`: its time and peak RSS, against an
 *  optional limit (the memory of a frame whatever its cut). */
[[nodiscard]] Result<BenchRun> prepareRender(const Scenario& scenario);

/** Compact geometry: every node's triangles of built scenes encoded as clusters (format v2's
 *  codec) per variant, bytes a triangle and decode rate, beside format v1 and Draco. */
[[nodiscard]] Result<BenchRun> prepareCodec(const Scenario& scenario);

/** Scene file formats 1 and 2 side by side: bytes a triangle, build time and memory, check rate. */
[[nodiscard]] Result<BenchRun> prepareFormat(const Scenario& scenario);

/** The prepare function of the scenario's kind. */
[[nodiscard]] Result<BenchRun> prepareScenario(const Scenario& scenario);

} // namespace ff::bench
