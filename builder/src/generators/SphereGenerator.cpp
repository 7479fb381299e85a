// sphere: one large, smooth, closed surface — the second of Chamberlain et al.'s tearing cases
// (§5.1): a contiguous surface much larger than the leaf cells, whose colour cubes seen off the
// sampled axes are nearly transparent at the silhouette and let the background through. A
// latitude-longitude tessellation with vertex normals, coloured by latitude so that errors in
// colour show as well as holes.

#include "GeneratorKit.h"

#include <array>
#include <vector>

namespace ff::builder::generators {

namespace {

constexpr std::array<ParamDef, 2> kParams = {{
        {"triangles", "100000", "triangles, about (>= 8; rounded to a whole latitude-longitude grid)"},
        {"radius", "10", "radius, units"},
}};

struct SphereParams {
    std::uint64_t rings = 0;    ///< latitude bands
    std::uint64_t segments = 0; ///< longitude steps, twice the bands: cells stay near square
    float radius = 0.0f;
};

Result<SphereParams> readParams(const GeneratorSpec& spec) {
    const ParamReader reader("sphere", spec, kParams);
    FF_RETURN_IF_ERROR(reader.checkKnownKeys());
    FF_ASSIGN_OR_RETURN(const std::uint64_t triangles, reader.integer("triangles", 8, 1'000'000'000));
    FF_ASSIGN_OR_RETURN(const double radius, reader.real("radius", 1e-6, 1e9));
    // Two caps of `segments` triangles and (rings - 2) bands of 2 * segments: about
    // 2 * rings * segments = 4 * rings^2 triangles.
    SphereParams p;
    p.rings = std::max<std::uint64_t>(2, static_cast<std::uint64_t>(std::sqrt(static_cast<double>(triangles) / 4.0) + 0.5));
    p.segments = 2 * p.rings;
    p.radius = static_cast<float>(radius);
    return p;
}

/** Linear RGB by latitude: warm at the south pole to cool at the north, varying smoothly. */
glm::vec4 latitudeColor(double v) {
    const auto t = static_cast<float>(v);
    return glm::vec4(0.80f - 0.45f * t, 0.45f + 0.15f * t, 0.30f + 0.55f * t, 1.0f);
}

Result<GeneratorReport> runSphere(const GeneratorSpec& spec, ISceneSink& sink) {
    FF_ASSIGN_OR_RETURN(const SphereParams p, readParams(spec));
    FF_ASSIGN_OR_RETURN(const PrototypeId prototype, sink.addPrototype("sphere"));

    // One ring of unit directions per latitude; ring 0 and ring `rings` are the poles.
    std::vector<SinCos> longitude(p.segments + 1);
    for (std::uint64_t j = 0; j <= p.segments; ++j)
        longitude[j] = sinCosTurns(static_cast<double>(j % p.segments) / static_cast<double>(p.segments));
    auto vertexAt = [&](std::uint64_t ring, std::uint64_t segment) {
        const double v = static_cast<double>(ring) / static_cast<double>(p.rings); // 0 south .. 1 north
        const SinCos latitude = sinCosTurns(0.5 * v - 0.25);
        const SinCos& around = longitude[segment];
        const glm::vec3 normal(static_cast<float>(latitude.cos * around.cos),
                               static_cast<float>(latitude.sin),
                               static_cast<float>(latitude.cos * around.sin));
        return SourceVertex{p.radius * normal, normal, latitudeColor(v)};
    };

    TriangleBatcher out(sink, prototype);
    for (std::uint64_t ring = 0; ring < p.rings; ++ring) {
        for (std::uint64_t j = 0; j < p.segments; ++j) {
            const SourceVertex a = vertexAt(ring, j);
            const SourceVertex b = vertexAt(ring, j + 1);
            const SourceVertex c = vertexAt(ring + 1, j + 1);
            const SourceVertex d = vertexAt(ring + 1, j);
            // Counter-clockwise seen from outside; the caps' degenerate halves are left out.
            if (ring > 0)
                FF_RETURN_IF_ERROR(out.add(a, c, b));
            if (ring + 1 < p.rings)
                FF_RETURN_IF_ERROR(out.add(a, d, c));
        }
    }
    FF_ASSIGN_OR_RETURN(const GeneratorReport report, flushSingleMesh(out));
    FF_RETURN_IF_ERROR(sink.addInstance(prototype, glm::dmat4(1.0)));
    FF_ASSERT(report.storedTriangles == 2 * p.segments * (p.rings - 1));
    return report;
}

} // namespace

GeneratorEntry sphereGenerator() {
    return {makeGeneratorInfo(
                    "sphere",
                    "one large smooth closed surface (latitude-longitude grid): colour cubes tear "
                    "on it off the sampled axes",
                    kParams),
            &runSphere};
}

} // namespace ff::builder::generators
