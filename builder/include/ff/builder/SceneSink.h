#pragma once

// The one door through which scene content enters the builder. Importers (glTF) and
// generators (forest, terrain, ...) push prototypes, triangles and instances into an ISceneSink;
// the builder behind it spills them to disk as they arrive, so no source ever has to
// materialise a whole scene.

#include <ff/storage/SceneFormat.h>
#include <ff/storage/Status.h>

#include <glm/glm.hpp>

#include <cstdint>
#include <span>
#include <string_view>

namespace ff::builder {

using PrototypeId = std::uint32_t;

/** A vertex as sources describe it: colour is linear RGBA (base colour x texture x vertex
 *  colour). A zero or non-finite normal means "use the triangle's face normal". */
struct SourceVertex {
    glm::vec3 position{0.0f};
    glm::vec3 normal{0.0f};
    glm::vec4 color{1.0f};
    bool unlit = false; ///< KHR_materials_unlit: stored with storage::kUnlitNormalOct
};

/** The regular grid an isosurface was extracted from: cells[a] cubes of edge cellSize along
 *  axis a from origin, each holding the triangles extracted in it (no triangle crosses a cell
 *  face). ORSD decomposes by it (HierarchyParams.h). */
struct VoxelGrid {
    glm::vec3 origin{0.0f};
    float cellSize = 1.0f;
    glm::uvec3 cells{0u};
};

/** Packs one vertex; a zero or non-finite normal is replaced by `fallbackNormal`. */
storage::PackedVertex packVertex(const SourceVertex& v, const glm::vec3& fallbackNormal) noexcept;

/** Packs three vertices into the on-disk/GPU triangle layout (positions unchanged). */
storage::PackedTriangle packTriangle(
        const SourceVertex& a, const SourceVertex& b, const SourceVertex& c) noexcept;

/**
 * Receives a scene as a stream. Calls may interleave freely: triangles can be added to any
 * declared prototype at any time; an instance may be added before its prototype has triangles.
 * Triangles with non-finite positions or zero area are dropped and counted by the sink, so
 * sources pass them through unchanged.
 */
class ISceneSink {
public:
    virtual ~ISceneSink() = default;

    /** Declares a prototype (a mesh stored once). `name` is informational. */
    [[nodiscard]] virtual Result<PrototypeId> addPrototype(std::string_view name) = 0;

    /** Appends triangles, in the prototype's own coordinate frame. */
    [[nodiscard]] virtual Status addTriangles(
            PrototypeId prototype, std::span<const storage::PackedTriangle> triangles) = 0;

    /** Places the prototype in the world with `transform` (affine, column-major glm; double, so
     *  scenes far from the world origin keep their precision until the builder picks the file frame). */
    [[nodiscard]] virtual Status addInstance(PrototypeId prototype, const glm::dmat4& transform) = 0;

    /** Says that the prototype's triangles were extracted cell by cell from `grid` (in the
     *  prototype's frame). Optional: sinks that have no use for it ignore it. */
    [[nodiscard]] virtual Status declareVoxelGrid(PrototypeId prototype, const VoxelGrid& grid) {
        (void)prototype;
        (void)grid;
        return Status::ok();
    }
};

} // namespace ff::builder
