#include "SceneInput.h"

#include <ff/builder/Generators.h>
#include <ff/builder/GltfImporter.h>

#include <nlohmann/json.hpp>

namespace ff::viewer {

namespace {

template <typename Vector>
nlohmann::json vec3Json(const Vector& v) {
    return {v.x, v.y, v.z};
}

glm::vec3 placedDirection(const glm::dmat4& placement, const glm::vec3& direction) {
    return glm::vec3(glm::normalize(glm::dmat3(placement) * glm::dvec3(direction)));
}

} // namespace

Result<SceneInputSummary> feedScene(
        const std::string& input,
        const std::string& generatorSpec,
        const glm::dmat4& placement,
        builder::ISceneSink& sink) {
    SceneInputSummary summary;
    nlohmann::json metadata = nlohmann::json::object();
    if (!generatorSpec.empty()) {
        FF_ASSIGN_OR_RETURN(const builder::GeneratorSpec spec, builder::parseGeneratorSpec(generatorSpec));
        FF_ASSIGN_OR_RETURN(const builder::GeneratorReport report, builder::runGenerator(spec, sink));
        summary.source = "generate:" + generatorSpec;
        summary.declaredTriangles = report.triangles;
        metadata["source"] = summary.source;
        metadata["cameras"] = nlohmann::json::array();
    } else {
        FF_ASSIGN_OR_RETURN(const builder::GltfImportReport report, builder::importGltf(input, sink));
        summary.source = input;
        summary.declaredTriangles = report.declaredTriangles;
        summary.warnings = report.warnings;
        metadata["source"] = input;
        nlohmann::json cameras = nlohmann::json::array();
        for (const builder::GltfCamera& c : report.cameras) {
            cameras.push_back({{"name", c.name},
                               {"perspective", c.perspective},
                               {"eye", vec3Json(glm::dvec3(placement * glm::dvec4(c.eye, 1.0)))},
                               {"forward", vec3Json(placedDirection(placement, c.forward))},
                               {"up", vec3Json(placedDirection(placement, c.up))},
                               {"yfov", c.yfovRadians},
                               {"aspect", c.aspectRatio},
                               {"znear", c.znear},
                               {"zfar", c.zfar},
                               {"xmag", c.xmag},
                               {"ymag", c.ymag}});
        }
        metadata["cameras"] = cameras;
        metadata["warnings"] = report.warnings;
    }
    metadata["declared_triangles"] = summary.declaredTriangles;
    summary.metadataJson = metadata.dump();
    return summary;
}

} // namespace ff::viewer
