// cathedral: Meißner, Bartz et al.'s low-occlusion scene (Table 1's "Cathedral", 417 k
// triangles): a basilica seen from inside. A nave under a barrel vault between two arcades of
// round pillars and arches, side aisles, a tiled floor. From the nave nearly everything is in
// view; the pillars hide a little of the aisles. Occlusion culling must not cost much here.
// One flat prototype (the builder's decomposition sees the whole interior); z runs from the west
// door (z = 0) to the east wall.

#include "GeneratorKit.h"

#include <array>
#include <cmath>

namespace ff::builder::generators {

namespace {

constexpr std::array<ParamDef, 2> kParams = {{
        {"bays", "12", "pillars along each arcade (2..256); the nave is 6.4 units a bay long"},
        {"detail",
         "1",
         "tessellation multiplier (1..16): 1 gives about 430 k triangles at 12 bays"},
}};

constexpr float kBay = 6.4f;         ///< pillar spacing along the nave
constexpr float kNaveHalf = 7.0f;    ///< the arcades stand at x = +-7
constexpr float kAisleOuter = 13.0f; ///< the outer walls at x = +-13
constexpr float kPillarRadius = 0.8f;
constexpr float kPillarHeight = 7.0f; ///< the arches spring here and rise half a bay
constexpr float kAisleHeight = 10.2f;
constexpr float kClerestoryTop = 16.0f; ///< the vault springs here, radius kNaveHalf

struct CathedralParams {
    std::uint32_t bays = 0;
    std::uint32_t detail = 0;
    float length() const { return kBay * static_cast<float>(bays + 1); }
};

Result<CathedralParams> readParams(const GeneratorSpec& spec) {
    const ParamReader reader("cathedral", spec, kParams);
    FF_RETURN_IF_ERROR(reader.checkKnownKeys());
    CathedralParams p;
    FF_ASSIGN_OR_RETURN(const std::uint64_t bays, reader.integer("bays", 2, 256));
    FF_ASSIGN_OR_RETURN(const std::uint64_t detail, reader.integer("detail", 1, 16));
    p.bays = static_cast<std::uint32_t>(bays);
    p.detail = static_cast<std::uint32_t>(detail);
    return p;
}

glm::vec4 stone(float shade) {
    return glm::vec4(0.62f * shade, 0.58f * shade, 0.50f * shade, 1.0f);
}

/** A grid of nu x nv quads spanning origin + [0,1] u + [0,1] v, facing normal. */
Status emitQuadGrid(
        const glm::vec3& origin,
        const glm::vec3& u,
        const glm::vec3& v,
        std::uint32_t nu,
        std::uint32_t nv,
        const glm::vec3& normal,
        const glm::vec4& color,
        TriangleBatcher& out) {
    auto at = [&](std::uint32_t i, std::uint32_t j) {
        return SourceVertex{
                origin + u * (static_cast<float>(i) / static_cast<float>(nu)) +
                        v * (static_cast<float>(j) / static_cast<float>(nv)),
                normal,
                color};
    };
    for (std::uint32_t j = 0; j < nv; ++j)
        for (std::uint32_t i = 0; i < nu; ++i) {
            FF_RETURN_IF_ERROR(out.add(at(i, j), at(i + 1, j), at(i + 1, j + 1)));
            FF_RETURN_IF_ERROR(out.add(at(i, j), at(i + 1, j + 1), at(i, j + 1)));
        }
    return Status::ok();
}

/** A surface of revolution about the vertical through `base`: `around` steps over the turns
 *  [from, to) of radius r(t) at height h(t) for t in [0, 1] over `rings` steps. */
template <typename Profile>
Status emitRevolution(
        const glm::vec3& base,
        std::uint32_t around,
        std::uint32_t rings,
        Profile&& profile,
        const glm::vec4& color,
        TriangleBatcher& out) {
    auto at = [&](std::uint32_t i, std::uint32_t j) {
        const SinCos a = sinCosTurns(static_cast<double>(i % around) / static_cast<double>(around));
        const auto [radius, height] = profile(static_cast<float>(j) / static_cast<float>(rings));
        const glm::vec3 n(static_cast<float>(a.cos), 0.0f, static_cast<float>(a.sin));
        return SourceVertex{base + glm::vec3(radius * n.x, height, radius * n.z), n, color};
    };
    for (std::uint32_t j = 0; j < rings; ++j)
        for (std::uint32_t i = 0; i < around; ++i) {
            FF_RETURN_IF_ERROR(out.add(at(i, j), at(i, j + 1), at(i + 1, j + 1)));
            FF_RETURN_IF_ERROR(out.add(at(i, j), at(i + 1, j + 1), at(i + 1, j)));
        }
    return Status::ok();
}

/** A semicircular arch in the plane x = x0 over [z0, z0 + span], springing at height y0: a
 *  swept square section `thickness` wide, `steps` along the arc (4 faces a step). */
Status emitArch(
        float x0,
        float z0,
        float y0,
        float span,
        float thickness,
        std::uint32_t steps,
        TriangleBatcher& out) {
    const float radius = 0.5f * span;
    const glm::vec3 centre(x0, y0, z0 + radius);
    const glm::vec4 color = stone(0.9f);
    auto ring = [&](std::uint32_t s, int corner) {
        const SinCos a = sinCosTurns(0.5 * static_cast<double>(s) / static_cast<double>(steps));
        const glm::vec3 radial(0.0f, static_cast<float>(a.sin), -static_cast<float>(a.cos));
        const float r = radius + ((corner & 1) ? 0.5f : -0.5f) * thickness;
        const float dx = ((corner & 2) ? 0.5f : -0.5f) * thickness;
        return centre + glm::vec3(dx, 0.0f, 0.0f) + r * radial;
    };
    // The four faces of the section: inner (0,2), outer (1,3), and the two sides.
    constexpr std::array<std::array<int, 2>, 4> kFaces = {{{0, 2}, {3, 1}, {1, 0}, {2, 3}}};
    for (std::uint32_t s = 0; s < steps; ++s)
        for (const auto& face : kFaces) {
            const glm::vec3 a = ring(s, face[0]), b = ring(s, face[1]);
            const glm::vec3 c = ring(s + 1, face[1]), d = ring(s + 1, face[0]);
            const glm::vec3 n(0.0f); // the face normal
            FF_RETURN_IF_ERROR(out.add({a, n, color}, {b, n, color}, {c, n, color}));
            FF_RETURN_IF_ERROR(out.add({a, n, color}, {c, n, color}, {d, n, color}));
        }
    return Status::ok();
}

Result<GeneratorReport> runCathedral(const GeneratorSpec& spec, ISceneSink& sink) {
    FF_ASSIGN_OR_RETURN(const CathedralParams p, readParams(spec));
    FF_ASSIGN_OR_RETURN(const PrototypeId prototype, sink.addPrototype("cathedral"));
    TriangleBatcher out(sink, prototype);
    const std::uint32_t d = p.detail;
    const float length = p.length();
    const std::uint32_t alongNave = 5 * (p.bays + 1) * d;

    // The floor, tiled in two shades (one quad a tile, 1 unit).
    const auto tilesX = static_cast<std::uint32_t>(2.0f * kAisleOuter);
    const auto tilesZ = static_cast<std::uint32_t>(length);
    for (std::uint32_t j = 0; j < tilesZ; ++j)
        for (std::uint32_t i = 0; i < tilesX; ++i) {
            const glm::vec3 origin(
                    -kAisleOuter + static_cast<float>(i), 0.0f, static_cast<float>(j));
            const glm::vec4 color = (i + j) % 2 ? glm::vec4(0.75f, 0.72f, 0.66f, 1.0f)
                                                : glm::vec4(0.28f, 0.26f, 0.25f, 1.0f);
            FF_RETURN_IF_ERROR(
                    emitQuadGrid(origin, {1, 0, 0}, {0, 0, 1}, 1, 1, {0, 1, 0}, color, out));
        }
    // Outer walls, the aisles' ceilings, the clerestory walls above the arcades, the end walls.
    for (const float side : {-1.0f, 1.0f}) {
        FF_RETURN_IF_ERROR(emitQuadGrid(
                {side * kAisleOuter, 0, 0},
                {0, 0, length},
                {0, kAisleHeight, 0},
                alongNave,
                10 * d,
                {-side, 0, 0},
                stone(0.8f),
                out));
        FF_RETURN_IF_ERROR(emitQuadGrid(
                {side * kNaveHalf, kAisleHeight, 0},
                {side * (kAisleOuter - kNaveHalf), 0, 0},
                {0, 0, length},
                6 * d,
                alongNave,
                {0, -1, 0},
                stone(0.7f),
                out));
        FF_RETURN_IF_ERROR(emitQuadGrid(
                {side * kNaveHalf, kAisleHeight, 0},
                {0, 0, length},
                {0, kClerestoryTop - kAisleHeight, 0},
                alongNave,
                6 * d,
                {-side, 0, 0},
                stone(0.85f),
                out));
    }
    for (const float z : {0.0f, length}) {
        const glm::vec3 facing(0.0f, 0.0f, z == 0.0f ? 1.0f : -1.0f);
        FF_RETURN_IF_ERROR(emitQuadGrid(
                {-kAisleOuter, 0, z},
                {2 * kAisleOuter, 0, 0},
                {0, kAisleHeight, 0},
                26 * d,
                10 * d,
                facing,
                stone(0.75f),
                out));
        FF_RETURN_IF_ERROR(emitQuadGrid(
                {-kNaveHalf, kAisleHeight, z},
                {2 * kNaveHalf, 0, 0},
                {0, kClerestoryTop + kNaveHalf - kAisleHeight, 0},
                14 * d,
                14 * d,
                facing,
                stone(0.75f),
                out));
    }
    // The barrel vault over the nave: a half cylinder along z, seen from below.
    {
        const std::uint32_t around = 192 * d;
        auto at = [&](std::uint32_t i, std::uint32_t j) {
            const SinCos a =
                    sinCosTurns(0.5 * static_cast<double>(i) / static_cast<double>(around));
            const glm::vec3 inward(-static_cast<float>(a.cos), -static_cast<float>(a.sin), 0.0f);
            const glm::vec3 position(
                    kNaveHalf * static_cast<float>(a.cos),
                    kClerestoryTop + kNaveHalf * static_cast<float>(a.sin),
                    length * static_cast<float>(j) / static_cast<float>(alongNave * 6));
            return SourceVertex{position, inward, stone(0.95f)};
        };
        for (std::uint32_t j = 0; j < alongNave * 6; ++j)
            for (std::uint32_t i = 0; i < around; ++i) {
                FF_RETURN_IF_ERROR(out.add(at(i, j), at(i + 1, j), at(i + 1, j + 1)));
                FF_RETURN_IF_ERROR(out.add(at(i, j), at(i + 1, j + 1), at(i, j + 1)));
            }
    }
    // The arcades: round pillars with a swelling base and capital, arches between them.
    for (const float side : {-1.0f, 1.0f}) {
        for (std::uint32_t b = 0; b < p.bays; ++b) {
            const glm::vec3 base(side * kNaveHalf, 0.0f, kBay * static_cast<float>(b + 1));
            FF_RETURN_IF_ERROR(emitRevolution(
                    base,
                    64 * d,
                    80 * d,
                    [](float t) {
                        // A plinth and a capital a quarter wider than the shaft.
                        const float swell = t < 0.05f ? 1.25f : (t > 0.93f ? 1.25f : 1.0f);
                        return std::pair<float, float>{kPillarRadius * swell, kPillarHeight * t};
                    },
                    stone(0.9f),
                    out));
            if (b + 1 < p.bays)
                FF_RETURN_IF_ERROR(
                        emitArch(side * kNaveHalf, base.z, kPillarHeight, kBay, 0.6f, 96 * d, out));
        }
    }
    FF_ASSIGN_OR_RETURN(const GeneratorReport report, flushSingleMesh(out));
    FF_RETURN_IF_ERROR(sink.addInstance(prototype, glm::dmat4(1.0)));
    return report;
}

} // namespace

GeneratorEntry cathedralGenerator() {
    return {makeGeneratorInfo(
                    "cathedral",
                    "a basilica seen from inside: nave, barrel vault, arcades of pillars and "
                    "arches "
                    "(Meißner et al.'s low-occlusion scene)",
                    kParams),
            &runCathedral};
}

} // namespace ff::builder::generators
