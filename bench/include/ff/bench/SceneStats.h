#pragma once

// What a scene file holds and what of it a viewer uses: the data behind `farfield stats`
// (docs/methods.md, "Scene statistics"). Three independent parts:
//
//   collectSceneStats   walks every node reachable from the header root and the prototype roots
//                       through SceneFile (bounds-checked, every page verified), counts nodes,
//                       triangles and pages, and splits the file's bytes by representation so
//                       that the parts add up to the file size exactly.
//   measureCubeUsage    runs selection alone (no GL, every page resident) over the standard
//                       camera paths and records which nodes were drawn as color cubes.
//   measureGltfInput / measureGeneratorInput
//                       what the input would weigh, to compare the file against.

#include <ff/storage/SceneFile.h>
#include <ff/storage/Status.h>

#include <nlohmann/json.hpp>

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace ff::bench {

/** Nodes of one level of one kind of hierarchy, with their cubes. */
struct LevelStats {
    std::uint64_t nodes = 0;
    std::uint64_t withCube = 0;
    std::uint64_t cubesDrawn = 0; ///< distinct nodes drawn as a cube (measureCubeUsage)
};

/** The input a scene was built from, in bytes. */
struct InputSize {
    std::string what;             ///< how the bytes were counted, one line
    std::uint64_t bytes = 0;      ///< geometry-bearing input (glTF JSON + buffers, or indexed mesh)
    std::uint64_t imageBytes = 0; ///< textures (glTF images), not in `bytes`
};

/** Which nodes the standard camera paths draw as cubes. */
struct CubeUsage {
    std::vector<std::string> paths; ///< "orbit", "flythrough"
    std::int64_t framesPerPath = 0;
    float epsilonPixels = 1.0f;
    int width = 640;
    int height = 480;
    std::uint64_t cubeDraws = 0; ///< cubes drawn, summed over all frames
    std::uint64_t nodesWithCube = 0;
    std::uint64_t nodesDrawn = 0;      ///< distinct nodes whose cube was drawn at least once
    std::uint64_t neverDrawn = 0;      ///< nodesWithCube - nodesDrawn
    std::uint64_t neverDrawnBytes = 0; ///< their cube bytes (24 each)
    std::uint64_t neverDrawnInstance = 0;
    std::uint64_t neverDrawnInner = 0; ///< cells with children
    std::uint64_t neverDrawnLeaf = 0;  ///< cells without children
    /** Leaves never drawn as a cube whose parent's cube was never drawn either. */
    std::uint64_t neverDrawnLeafWithNeverDrawnParent = 0;
};

/** Everything `farfield stats` reports. Byte fields are exact and sum to fileBytes. */
struct SceneStats {
    std::string path;
    std::uint64_t fileBytes = 0;
    std::uint32_t pageSize = 0;
    std::uint64_t pageCount = 0;
    std::string source; ///< metadata "source" (glTF path or "generate:SPEC"), may be empty

    // Nodes, by what they are.
    std::uint64_t nodes = 0;           ///< distinct records reachable from the roots
    std::uint64_t headerNodeCount = 0; ///< FileHeader::nodeCount
    std::uint64_t instanceLevelNodes = 0;
    std::uint64_t prototypeNodes = 0;
    std::uint64_t instanceNodes = 0;           ///< kind Instance
    std::uint64_t innerCells = 0;              ///< Cell with children
    std::uint64_t leafCells = 0;               ///< Cell without children
    std::uint64_t innerCellsWithTriangles = 0; ///< inner cells holding large triangles
    std::uint64_t singleChildCells = 0; ///< inner cells with one child and no triangles (chains)
    std::uint64_t emptyLeaves = 0;      ///< leaves without triangles
    std::uint64_t smallLeaves = 0;      ///< leaves with 1..7 triangles
    std::uint64_t nodesWithCube = 0;
    std::uint64_t maxChildren = 0;
    std::vector<LevelStats> prototypeLevels; ///< index = NodeRecord::level
    std::vector<LevelStats> instanceLevels;

    // Triangles and instancing.
    std::uint64_t storedTriangles = 0;    ///< sum of the reached cells' geometryCount
    std::uint64_t instancedTriangles = 0; ///< FileHeader::instancedTriangles (as drawn)
    std::uint64_t prototypes = 0;
    std::uint64_t instances = 0;

    // Pages.
    std::uint64_t nodePages = 0;
    std::uint64_t geometryPages = 0;
    std::uint64_t tablePages = 0;
    std::uint64_t unreferencedPages = 0;   ///< Nodes/Geometry pages nothing reachable uses
    std::uint64_t sparseNodePages = 0;     ///< Nodes pages less than a quarter full
    std::uint64_t sparseGeometryPages = 0; ///< Geometry pages less than a quarter full

    // Bytes by representation (sum = fileBytes).
    std::uint64_t headerBytes = 0;     ///< FileHeader + section table
    std::uint64_t nodeRecordBytes = 0; ///< 96 per node, cubes included
    std::uint64_t cubeBytes = 0;       ///< 24 per node with a cube (part of nodeRecordBytes)
    std::uint64_t triangleBytes = 0;   ///< 60 per stored triangle
    std::uint64_t prototypeRecordBytes = 0;
    std::uint64_t instanceRecordBytes = 0; ///< the instance transforms
    std::uint64_t metadataBytes = 0;
    std::uint64_t trailerBytes = 0;      ///< 16 per page
    std::uint64_t headerSlack = 0;       ///< unused payload of page 0
    std::uint64_t nodeSlack = 0;         ///< unused slots and tail bytes of Nodes pages
    std::uint64_t geometrySlack = 0;     ///< same for Geometry pages
    std::uint64_t tableSlack = 0;        ///< tail of the last page of each table section
    std::uint64_t unreferencedBytes = 0; ///< payload of unreferenced pages

    std::optional<InputSize> input;
    std::optional<CubeUsage> cubes;

    std::uint64_t representedBytes() const noexcept;
    nlohmann::json toJson() const;
};

/** Walks the whole file. Verifies every page first (as `farfield check`); errors name the page. */
[[nodiscard]] Result<SceneStats> collectSceneStats(const storage::SceneFile& scene);

struct CubeUsageOptions {
    std::vector<std::string> paths = {"orbit", "flythrough"};
    std::int64_t framesPerPath = 60;
    float epsilonPixels = 1.0f;
    int width = 640;
    int height = 480;
};

/** Selects every frame of the paths (fitted to the scene's bounds, as `farfield path` makes
 *  them) with every page resident and fills stats.cubes. Needs collectSceneStats' walk first. */
[[nodiscard]] Status measureCubeUsage(
        const storage::SceneFile& scene, const CubeUsageOptions& options, SceneStats& stats);

/** A .gltf with its external buffers (and, apart, images), or a .glb less its embedded images. */
[[nodiscard]] Result<InputSize> measureGltfInput(const std::filesystem::path& file);

/** Runs the generator and counts the indexed mesh it amounts to: per prototype, 20 bytes per
 *  distinct vertex (the file's PackedVertex) and 12 per triangle (u32 indices), plus 48 bytes per
 *  instance (a 3x4 float transform). */
[[nodiscard]] Result<InputSize> measureGeneratorInput(const std::string& spec);

} // namespace ff::bench
