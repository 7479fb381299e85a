#pragma once

#include <ff/storage/Status.h>

#include <filesystem>
#include <string>

namespace ff::viewer::bench {

struct BenchOptions {
    std::filesystem::path outDir = "docs/results";
    std::filesystem::path workDir; ///< scene files (large; default: outDir/scenes, removed after)
    bool quick = false;            ///< smaller ladders, fewer repetitions (smoke runs)
    int timedFrames = 3;
    std::string selfExe;           ///< this executable, for child builds
};

/** Chamberlain et al. '96 Table 2 on the tree: full vs hierarchical at d = 1.75..14 radii. */
[[nodiscard]] Status runTable2(const BenchOptions& options);
/** The recursively instanced forest, 1 to 16384 trees, at one fixed view (log-log chart). */
[[nodiscard]] Status runForest(const BenchOptions& options);
/** Working set of a complete frame against scene size; cold-cache teleports on a terrain. */
[[nodiscard]] Status runPaging(const BenchOptions& options);
/** Builder throughput and peak RSS on terrain ladders. */
[[nodiscard]] Status runBuild(const BenchOptions& options);

} // namespace ff::viewer::bench
