#pragma once

#include "PrototypeBuilder.h"

#include <ff/builder/HierarchyParams.h>
#include <ff/storage/SceneFormat.h>
#include <ff/storage/SceneWriter.h>
#include <ff/storage/Status.h>

#include <cstdint>
#include <vector>

namespace ff::builder {

struct InstanceLevelResult {
    storage::NodeRef root{};    ///< v1
    std::uint32_t rootNode = 0; ///< v2: node index
    glm::vec3 boundsMin{0.0f};
    glm::vec3 boundsMax{0.0f};
    std::uint64_t nodes = 0;
    std::uint64_t nodePages = 0;
    std::uint32_t depth = 0;
};

/**
 * Builds the instance-level hierarchy: an octree (or the bounding-volume decomposition
 * `params.decomposition` names; ORSD builds the octree) over the instances' world bounds whose
 * leaves are Instance nodes pointing at prototypes. Every node's color cube is baked from its
 * instances' prototype cells (a cut of the prototype hierarchy whose cells are about one bake
 * sample across), transformed into the world: instances are never expanded into triangles.
 */
[[nodiscard]] Result<InstanceLevelResult> buildInstanceLevel(
        storage::SceneWriter& writer,
        const std::vector<storage::InstanceRecord>& instances,
        const std::vector<storage::PrototypeRecord>& prototypes,
        const std::vector<PrototypeSummary>& summaries,
        const HierarchyParams& params,
        NodePageTable* nodePageTable = nullptr);

/** The glm matrix of a stored row-major 3x4 transform, and back. */
glm::mat4 toMat4(const std::array<float, 12>& rowMajor3x4);
std::array<float, 12> toRowMajor3x4(const glm::mat4& m);

} // namespace ff::builder
