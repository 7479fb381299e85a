#pragma once

#include <ff/builder/SceneSink.h>
#include <ff/storage/Status.h>

#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <vector>

namespace ff::builder {

/** "forest:trees=16384,seed=7" parsed into a name and key=value parameters. */
struct GeneratorSpec {
    std::string name;
    std::map<std::string, std::string, std::less<>> params;
};

/** Parses NAME[:key=value,...]. Errors: InvalidArgument naming the bad part. */
[[nodiscard]] Result<GeneratorSpec> parseGeneratorSpec(std::string_view text);

struct GeneratorInfo {
    std::string name;
    std::string summary; ///< one line for --help
    std::vector<std::pair<std::string, std::string>> params; ///< key, "default: meaning"
};

/** Every generator with its parameters, for --help. */
const std::vector<GeneratorInfo>& generatorCatalog();

struct GeneratorReport {
    std::uint64_t triangles = 0; ///< as drawn (instances counted)
    std::uint64_t storedTriangles = 0; ///< passed to the sink (prototypes counted once)
    std::uint32_t prototypes = 0;
    std::uint64_t instances = 0;
};

/**
 * Streams the generated scene into `sink` in batches, never materialising it: memory use is
 * independent of the scene size. Deterministic: the same spec gives the same triangles, in the
 * same order, on every machine. Errors: InvalidArgument for an unknown generator or parameter.
 *
 *  - forest:trees=N (N a power of 4, 1..16384+), seed   — one ~50k-triangle tree instanced in a
 *    recursive 2x2 layout (Chamberlain et al. §5.2)
 *  - terrain:triangles=N, seed — a flat, non-instanced coloured heightfield
 *  - molecule:spheres=N, seed  — spheres of a few element prototypes, instanced
 *  - blinds:slabs=N            — closely spaced parallel thin slabs in one prototype
 *  - sphere:triangles=N,radius — one large smooth closed surface (latitude-longitude grid)
 *  - city:blocks=N,floors,items,instanced — closed furnished buildings along streets (occlusion)
 *  - cathedral:bays=N,detail — a basilica seen from inside (low occlusion)
 *  - isosurface:resolution=N,seed — chambers and tubes extracted from a voxel grid (declares
 *    the grid to the sink: ORSD)
 */
[[nodiscard]] Result<GeneratorReport> runGenerator(const GeneratorSpec& spec, ISceneSink& sink);

} // namespace ff::builder
