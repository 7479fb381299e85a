#pragma once

#include <ff/builder/SceneSink.h>
#include <ff/storage/Status.h>

#include <cstdint>
#include <string>
#include <vector>

namespace ff::viewer {

/** What a source put into the sink, for the build report and the file's metadata. */
struct SceneInputSummary {
    std::string source;       ///< the glTF path or the generator spec
    std::string metadataJson; ///< {"source": ..., "cameras": [...], "declared_triangles": ...}
    std::uint64_t declaredTriangles = 0;
    std::vector<std::string> warnings;
};

/** Streams a glTF file (`input`) or a generator (`generatorSpec`) into `sink`. The glTF's
 *  cameras go into the metadata in world space, moved by `placement` as the builder moves the
 *  geometry (BuildOptions::placement). */
[[nodiscard]] Result<SceneInputSummary> feedScene(
        const std::string& input,
        const std::string& generatorSpec,
        const glm::dmat4& placement,
        builder::ISceneSink& sink);

} // namespace ff::viewer
