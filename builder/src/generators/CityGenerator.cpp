// city: Meißner, Bartz et al.'s "City" (occlusion culling's test scene, Table 1): an n x n grid
// of closed buildings along streets, whose furnished interiors hold most of the triangles and
// are never seen from outside. From the street, a few facades hide nearly everything: the scene
// where occlusion culling pays most and frustum culling least.
//
// instanced=1: a shell prototype per building height and three furniture prototypes, placed by
// instances (a building is its shell plus its furniture). instanced=0: the same triangles in one
// flat prototype, so the builder's octree sees walls and furniture side by side.

#include "GeneratorKit.h"

#include <array>

namespace ff::builder::generators {

namespace {

constexpr std::array<ParamDef, 5> kParams = {{
        {"blocks", "16", "buildings along each side of the square grid (1..256)"},
        {"floors", "4", "storeys of the tallest building; each building has 1..floors (1..64)"},
        {"items", "6", "pieces of furniture per storey (0..256)"},
        {"instanced",
         "1",
         "1: shells and furniture are prototypes placed by instances; 0: one flat prototype"},
        {"seed", "1", "layout and colours"},
}};

constexpr float kPitch = 20.0f; ///< building grid spacing (a 12-unit building, an 8-unit street)
constexpr float kFootprint = 12.0f; ///< a building's side
constexpr float kStorey = 3.0f;     ///< height of a storey
constexpr float kWall = 0.2f;       ///< thickness of floors

struct CityParams {
    std::uint32_t blocks = 0;
    std::uint32_t floors = 0;
    std::uint32_t items = 0;
    bool instanced = true;
    std::uint64_t seed = 0;
};

Result<CityParams> readParams(const GeneratorSpec& spec) {
    const ParamReader reader("city", spec, kParams);
    FF_RETURN_IF_ERROR(reader.checkKnownKeys());
    CityParams p;
    FF_ASSIGN_OR_RETURN(const std::uint64_t blocks, reader.integer("blocks", 1, 256));
    FF_ASSIGN_OR_RETURN(const std::uint64_t floors, reader.integer("floors", 1, 64));
    FF_ASSIGN_OR_RETURN(const std::uint64_t items, reader.integer("items", 0, 256));
    FF_ASSIGN_OR_RETURN(const std::uint64_t instanced, reader.integer("instanced", 0, 1));
    FF_ASSIGN_OR_RETURN(p.seed, reader.integer("seed", 0, UINT64_MAX));
    p.blocks = static_cast<std::uint32_t>(blocks);
    p.floors = static_cast<std::uint32_t>(floors);
    p.items = static_cast<std::uint32_t>(items);
    p.instanced = instanced == 1;
    return p;
}

// Furniture, in a unit frame (on the floor at y = 0, about a metre across), each piece a few
// hundred triangles so that a piece is worth an occlusion test on its own.
constexpr std::array<std::uint32_t, 3> kFine = {5, 5, 5};
constexpr std::array<std::uint32_t, 3> kCoarse = {1, 1, 1};

Status emitTable(TriangleBatcher& out, const glm::mat4& m) {
    const glm::vec4 wood(0.45f, 0.28f, 0.14f, 1.0f);
    const auto box = [&](const glm::vec3& lo,
                         const glm::vec3& hi,
                         const std::array<std::uint32_t, 3>& s) {
        Box b = axisBox(glm::vec3(m * glm::vec4(lo, 1.0f)), glm::vec3(m * glm::vec4(hi, 1.0f)));
        return emitBox(b, s, wood, out);
    };
    FF_RETURN_IF_ERROR(box({-0.8f, 0.72f, -0.5f}, {0.8f, 0.8f, 0.5f}, kFine));
    for (const float x : {-0.7f, 0.62f})
        for (const float z : {-0.4f, 0.32f})
            FF_RETURN_IF_ERROR(box({x, 0.0f, z}, {x + 0.08f, 0.72f, z + 0.08f}, kCoarse));
    return Status::ok();
}

Status emitShelf(TriangleBatcher& out, const glm::mat4& m) {
    const glm::vec4 paint(0.62f, 0.64f, 0.58f, 1.0f);
    const Box b =
            axisBox(glm::vec3(m * glm::vec4(-0.5f, 0.0f, -0.2f, 1.0f)),
                    glm::vec3(m * glm::vec4(0.5f, 2.0f, 0.2f, 1.0f)));
    return emitBox(b, {5, 8, 3}, paint, out);
}

Status emitSofa(TriangleBatcher& out, const glm::mat4& m) {
    const glm::vec4 cloth(0.30f, 0.36f, 0.62f, 1.0f);
    const auto box = [&](const glm::vec3& lo, const glm::vec3& hi) {
        Box b = axisBox(glm::vec3(m * glm::vec4(lo, 1.0f)), glm::vec3(m * glm::vec4(hi, 1.0f)));
        return emitBox(b, kFine, cloth, out);
    };
    FF_RETURN_IF_ERROR(box({-1.0f, 0.0f, -0.45f}, {1.0f, 0.45f, 0.45f}));
    FF_RETURN_IF_ERROR(box({-1.0f, 0.45f, 0.25f}, {1.0f, 0.9f, 0.45f}));
    return Status::ok();
}

using FurnitureEmitter = Status (*)(TriangleBatcher&, const glm::mat4&);
constexpr std::array<FurnitureEmitter, 3> kFurniture = {&emitTable, &emitShelf, &emitSofa};

/** A building's closed shell (walls and roof as one tessellated box) and its storeys' floors,
 *  in the building's frame: footprint centred on the origin, ground at y = 0. */
Status
emitShell(TriangleBatcher& out, const glm::mat4& m, std::uint32_t storeys, const glm::vec4& color) {
    const float height = kStorey * static_cast<float>(storeys);
    const float half = 0.5f * kFootprint;
    const Box shell =
            axisBox(glm::vec3(m * glm::vec4(-half, 0.0f, -half, 1.0f)),
                    glm::vec3(m * glm::vec4(half, height, half, 1.0f)));
    FF_RETURN_IF_ERROR(emitBox(shell, {4, 2 * storeys, 4}, color, out));
    const glm::vec4 floorColor(0.55f, 0.5f, 0.45f, 1.0f);
    for (std::uint32_t s = 1; s < storeys; ++s) {
        const float y = kStorey * static_cast<float>(s);
        const Box slab =
                axisBox(glm::vec3(m * glm::vec4(-half + kWall, y - kWall, -half + kWall, 1.0f)),
                        glm::vec3(m * glm::vec4(half - kWall, y, half - kWall, 1.0f)));
        FF_RETURN_IF_ERROR(emitBox(slab, {2, 1, 2}, floorColor, out));
    }
    return Status::ok();
}

/** Where a piece of furniture stands: its kind and its transform in the building's frame. */
struct Placement {
    std::uint32_t kind;
    glm::mat4 transform;
};

Placement placeFurniture(SplitMix64& rng, std::uint32_t storey) {
    const float reach = 0.5f * kFootprint - 1.5f;
    const glm::vec3 at(
            rng.uniform(-reach, reach),
            kStorey * static_cast<float>(storey),
            rng.uniform(-reach, reach));
    const std::uint32_t kind = rng.below(static_cast<std::uint32_t>(kFurniture.size()));
    return {kind, makeTransform(at, static_cast<double>(rng.below(4)) * 0.25, 1.0f)};
}

glm::mat4 buildingTransform(const CityParams& p, std::uint32_t i, std::uint32_t j) {
    const float offset = -0.5f * kPitch * static_cast<float>(p.blocks - 1);
    return makeTransform(
            glm::vec3(
                    offset + kPitch * static_cast<float>(i),
                    0.0f,
                    offset + kPitch * static_cast<float>(j)),
            0.0,
            1.0f);
}

Result<GeneratorReport> runCity(const GeneratorSpec& spec, ISceneSink& sink) {
    FF_ASSIGN_OR_RETURN(const CityParams p, readParams(spec));
    GeneratorReport report;
    const glm::vec4 groundColor(0.32f, 0.33f, 0.35f, 1.0f);
    const float extent = 0.5f * kPitch * static_cast<float>(p.blocks);
    const Box ground = axisBox({-extent, -0.2f, -extent}, {extent, 0.0f, extent});
    const std::array<std::uint32_t, 3> groundSegments = {p.blocks, 1, p.blocks};

    if (!p.instanced) {
        FF_ASSIGN_OR_RETURN(const PrototypeId city, sink.addPrototype("city"));
        TriangleBatcher out(sink, city);
        FF_RETURN_IF_ERROR(emitBox(ground, groundSegments, groundColor, out));
        for (std::uint32_t i = 0; i < p.blocks; ++i) {
            for (std::uint32_t j = 0; j < p.blocks; ++j) {
                SplitMix64 rng(streamSeed(p.seed, (std::uint64_t{i} << 32) | j));
                const std::uint32_t storeys = 1 + rng.below(p.floors);
                const glm::vec4 color(
                        rng.uniform(0.5f, 0.8f),
                        rng.uniform(0.45f, 0.7f),
                        rng.uniform(0.4f, 0.6f),
                        1.0f);
                const glm::mat4 building = buildingTransform(p, i, j);
                FF_RETURN_IF_ERROR(emitShell(out, building, storeys, color));
                for (std::uint32_t s = 0; s < storeys; ++s)
                    for (std::uint32_t k = 0; k < p.items; ++k) {
                        const Placement item = placeFurniture(rng, s);
                        FF_RETURN_IF_ERROR(kFurniture[item.kind](out, building * item.transform));
                    }
            }
        }
        FF_ASSIGN_OR_RETURN(report, flushSingleMesh(out));
        FF_RETURN_IF_ERROR(sink.addInstance(city, glm::dmat4(1.0)));
        return report;
    }

    // Instanced: the ground, a shell per storey count (one colour each), three furniture pieces.
    FF_ASSIGN_OR_RETURN(const PrototypeId groundPrototype, sink.addPrototype("ground"));
    {
        TriangleBatcher out(sink, groundPrototype);
        FF_RETURN_IF_ERROR(emitBox(ground, groundSegments, groundColor, out));
        FF_RETURN_IF_ERROR(out.flush());
        report.storedTriangles += out.added();
        report.triangles += out.added();
    }
    FF_RETURN_IF_ERROR(sink.addInstance(groundPrototype, glm::dmat4(1.0)));
    std::vector<PrototypeId> shells;
    std::vector<std::uint64_t> shellTriangles;
    for (std::uint32_t storeys = 1; storeys <= p.floors; ++storeys) {
        FF_ASSIGN_OR_RETURN(const PrototypeId shell, sink.addPrototype("shell"));
        SplitMix64 rng(streamSeed(p.seed, 0xC0102ull + storeys));
        const glm::vec4 color(
                rng.uniform(0.5f, 0.8f), rng.uniform(0.45f, 0.7f), rng.uniform(0.4f, 0.6f), 1.0f);
        TriangleBatcher out(sink, shell);
        FF_RETURN_IF_ERROR(emitShell(out, glm::mat4(1.0f), storeys, color));
        FF_RETURN_IF_ERROR(out.flush());
        shells.push_back(shell);
        shellTriangles.push_back(out.added());
        report.storedTriangles += out.added();
    }
    std::array<PrototypeId, kFurniture.size()> furniture{};
    std::array<std::uint64_t, kFurniture.size()> furnitureTriangles{};
    for (std::size_t f = 0; f < kFurniture.size(); ++f) {
        FF_ASSIGN_OR_RETURN(furniture[f], sink.addPrototype("furniture"));
        TriangleBatcher out(sink, furniture[f]);
        FF_RETURN_IF_ERROR(kFurniture[f](out, glm::mat4(1.0f)));
        FF_RETURN_IF_ERROR(out.flush());
        furnitureTriangles[f] = out.added();
        report.storedTriangles += out.added();
    }
    report.prototypes = static_cast<std::uint32_t>(1 + shells.size() + furniture.size());
    report.instances = 1;
    for (std::uint32_t i = 0; i < p.blocks; ++i) {
        for (std::uint32_t j = 0; j < p.blocks; ++j) {
            SplitMix64 rng(streamSeed(p.seed, (std::uint64_t{i} << 32) | j));
            const std::uint32_t storeys = 1 + rng.below(p.floors);
            (void)rng.uniform(0.0f, 1.0f); // the flat variant's colour draws, so both place alike
            (void)rng.uniform(0.0f, 1.0f);
            (void)rng.uniform(0.0f, 1.0f);
            const glm::mat4 building = buildingTransform(p, i, j);
            FF_RETURN_IF_ERROR(sink.addInstance(shells[storeys - 1], glm::dmat4(building)));
            report.triangles += shellTriangles[storeys - 1];
            ++report.instances;
            for (std::uint32_t s = 0; s < storeys; ++s)
                for (std::uint32_t k = 0; k < p.items; ++k) {
                    const Placement item = placeFurniture(rng, s);
                    FF_RETURN_IF_ERROR(sink.addInstance(
                            furniture[item.kind], glm::dmat4(building * item.transform)));
                    report.triangles += furnitureTriangles[item.kind];
                    ++report.instances;
                }
        }
    }
    return report;
}

} // namespace

GeneratorEntry cityGenerator() {
    return {makeGeneratorInfo(
                    "city",
                    "an n x n grid of closed buildings with furnished interiors along streets "
                    "(Meißner et al.'s occlusion-culling City), instanced or flat",
                    kParams),
            &runCity};
}

} // namespace ff::builder::generators
