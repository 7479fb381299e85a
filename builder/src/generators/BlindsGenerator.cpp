// blinds: closely spaced parallel thin slabs, the "venetian blind" that Chamberlain et al. '96
// (§3.2) name as the worst case for a six-sample colour cube: a
// small change of view direction flips the cluster between opaque and see-through. One
// prototype, one identity instance, so the builder sees the slabs as ordinary geometry.

#include "GeneratorKit.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace ff::builder::generators {

namespace {

constexpr std::array<ParamDef, 7> kParams = {{
        {"slabs", "100", "number of slabs, stacked along +Y (1..10000000)"},
        {"spacing", "0.1", "distance between neighbouring slab centres, units"},
        {"thickness", "0.02", "slab thickness along Y, units (less than spacing)"},
        {"width", "10", "slab extent along X, units"},
        {"depth", "1", "slab extent along Z, units"},
        {"tilt", "0", "slat angle about the X axis, degrees (-89..89)"},
        {"tessellation", "1", "quads along each slab's width (and as many per unit along its depth): "
                              "lets the octree split the slabs into cells (1..4096)"},
}};


// Light colours (linear RGB) that differ enough to alias visibly at a grazing angle.
constexpr std::array<glm::vec4, 2> kSlabColors = {
        glm::vec4(0.85f, 0.80f, 0.66f, 1.0f), // cream
        glm::vec4(0.55f, 0.68f, 0.86f, 1.0f), // pale blue
};

struct BlindsParams {
    std::uint64_t slabs = 0;
    float spacing = 0.0f;
    float thickness = 0.0f;
    float width = 0.0f;
    float depth = 0.0f;
    double tiltDegrees = 0.0;
    std::array<std::uint32_t, 3> segments{1, 1, 1}; ///< quads along the slab's X, Y (thickness), Z

    std::uint64_t trianglesPerSlab() const {
        const std::uint64_t x = segments[0], y = segments[1], z = segments[2];
        return 4 * (x * y + y * z + z * x);
    }
};

Result<BlindsParams> readParams(const GeneratorSpec& spec) {
    const ParamReader reader("blinds", spec, kParams);
    FF_RETURN_IF_ERROR(reader.checkKnownKeys());
    BlindsParams p;
    FF_ASSIGN_OR_RETURN(p.slabs, reader.integer("slabs", 1, 10'000'000));
    FF_ASSIGN_OR_RETURN(const double spacing, reader.real("spacing", 1e-4, 1e4));
    FF_ASSIGN_OR_RETURN(const double thickness, reader.real("thickness", 1e-5, 1e4));
    FF_ASSIGN_OR_RETURN(const double width, reader.real("width", 1e-3, 1e6));
    FF_ASSIGN_OR_RETURN(const double depth, reader.real("depth", 1e-3, 1e6));
    FF_ASSIGN_OR_RETURN(p.tiltDegrees, reader.real("tilt", -89.0, 89.0));
    FF_ASSIGN_OR_RETURN(const std::uint64_t tessellation, reader.integer("tessellation", 1, 4096));
    if (!(thickness < spacing))
        return reader.invalid("thickness", "must be less than spacing, or the slabs intersect");
    p.spacing = static_cast<float>(spacing);
    p.thickness = static_cast<float>(thickness);
    p.width = static_cast<float>(width);
    p.depth = static_cast<float>(depth);
    const double alongDepth = std::round(static_cast<double>(tessellation) * depth / width);
    p.segments = {static_cast<std::uint32_t>(tessellation), 1u, static_cast<std::uint32_t>(std::clamp(alongDepth, 1.0, 4096.0))};
    return p;
}

Result<GeneratorReport> runBlinds(const GeneratorSpec& spec, ISceneSink& sink) {
    FF_ASSIGN_OR_RETURN(const BlindsParams p, readParams(spec));
    FF_ASSIGN_OR_RETURN(const PrototypeId prototype, sink.addPrototype("blinds"));

    const SinCos tilt = sinCosTurns(p.tiltDegrees / 360.0);
    const auto c = static_cast<float>(tilt.cos);
    const auto s = static_cast<float>(tilt.sin);
    Box box{};
    box.axis = {glm::vec3(1, 0, 0), glm::vec3(0, c, s), glm::vec3(0, -s, c)};
    box.half = {0.5f * p.width, 0.5f * p.thickness, 0.5f * p.depth};

    TriangleBatcher out(sink, prototype);
    // Centred on the origin: slab k sits at y = (k - (n-1)/2) * spacing.
    const double middle = 0.5 * static_cast<double>(p.slabs - 1);
    for (std::uint64_t k = 0; k < p.slabs; ++k) {
        const double offset = (static_cast<double>(k) - middle) * static_cast<double>(p.spacing);
        box.center = glm::vec3(0.0f, static_cast<float>(offset), 0.0f);
        FF_RETURN_IF_ERROR(emitBox(box, p.segments, kSlabColors[k % kSlabColors.size()], out));
    }
    FF_ASSIGN_OR_RETURN(const GeneratorReport report, flushSingleMesh(out));
    FF_RETURN_IF_ERROR(sink.addInstance(prototype, glm::dmat4(1.0)));
    FF_ASSERT(report.storedTriangles == p.slabs * p.trianglesPerSlab());
    return report;
}

} // namespace

GeneratorEntry blindsGenerator() {
    return {makeGeneratorInfo(
                    "blinds",
                    "closely spaced thin parallel slabs in one prototype: the colour cube's "
                    "worst case (venetian blind)",
                    kParams),
            &runBlinds};
}

} // namespace ff::builder::generators
