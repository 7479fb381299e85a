// isosurface: Meißner, Bartz et al.'s "ventricular system" stand-in (Table 1, 270 k triangles):
// the zero set of a procedural volume, a ventricle-like system of chambers joined by tubes
// (two C-shaped lateral ventricles, a third ventricle between them, an aqueduct down to a flat
// fourth ventricle, and seeded side branches), extracted cell by cell on a regular grid with
// marching tetrahedra. Each grid cube is cut into the six tetrahedra around its main diagonal
// (Kuhn's triangulation, consistent across shared faces, so the surface is closed); a
// tetrahedron with one or three corners inside gives a triangle, one with two gives a quad.
// Every triangle lies inside the cube it came from: the builder is told the grid
// (ISceneSink::declareVoxelGrid), which ORSD decomposes by.

#include "GeneratorKit.h"

#include <algorithm>
#include <array>
#include <vector>

namespace ff::builder::generators {

namespace {

constexpr std::array<ParamDef, 2> kParams = {{
        {"resolution",
         "160",
         "grid cells along each axis (16..1024): 160 gives about 305 k triangles"},
        {"seed", "1", "placement of the side branches"},
}};

constexpr float kScale = 20.0f; ///< the field lives in [-1, 1]^3; the scene is 40 units across

/** A tube: a segment with radii at its ends. */
struct Tube {
    glm::vec3 a;
    glm::vec3 b;
    float ra;
    float rb;
};

/** An ellipsoid by its centre and radii. */
struct Chamber {
    glm::vec3 centre;
    glm::vec3 radii;
};

float clamp01(float x) {
    return x < 0.0f ? 0.0f : (x > 1.0f ? 1.0f : x);
}

/** Polynomial smooth minimum (blends over k): joins chambers and tubes without creases. */
float smoothMin(float a, float b, float k) {
    const float h = clamp01(0.5f + 0.5f * (b - a) / k);
    return b + (a - b) * h - k * h * (1.0f - h);
}

float tubeDistance(const Tube& t, const glm::vec3& p) {
    const glm::vec3 ab = t.b - t.a;
    const float s = clamp01(glm::dot(p - t.a, ab) / glm::dot(ab, ab));
    const glm::vec3 d = p - (t.a + ab * s);
    return std::sqrt(glm::dot(d, d)) - (t.ra + (t.rb - t.ra) * s);
}

float chamberDistance(const Chamber& c, const glm::vec3& p) {
    // Not a true distance, but zero on the surface and of the right sign, with a gradient
    // that does not vanish: what the iso-extraction and the blend need.
    const glm::vec3 q = (p - c.centre) / c.radii;
    const float smallest = std::min({c.radii.x, c.radii.y, c.radii.z});
    return (std::sqrt(glm::dot(q, q)) - 1.0f) * smallest;
}

class VentricleField {
public:
    explicit VentricleField(std::uint64_t seed) {
        mChambers.push_back(
                {glm::vec3(0.0f, 0.0f, 0.05f), glm::vec3(0.07f, 0.30f, 0.38f)}); // third
        mChambers.push_back(
                {glm::vec3(0.0f, -0.72f, -0.62f), glm::vec3(0.26f, 0.16f, 0.09f)}); // fourth
        mTubes.push_back(
                {glm::vec3(0.0f, -0.22f, -0.28f),
                 glm::vec3(0.0f, -0.66f, -0.58f),
                 0.045f,
                 0.035f}); // aqueduct
        SplitMix64 rng(streamSeed(seed, 0x7E47));
        for (const float side : {-1.0f, 1.0f}) {
            // A lateral ventricle: a C in the y-z plane, thick at its body, thin at its horns.
            constexpr int kSegments = 14;
            std::array<glm::vec3, kSegments + 1> points{};
            std::array<float, kSegments + 1> radii{};
            for (int i = 0; i <= kSegments; ++i) {
                const float u = static_cast<float>(i) / kSegments;
                const SinCos sc = sinCosTurns(0.08 + 0.74 * static_cast<double>(u));
                const float bulge = 4.0f * u * (1.0f - u);
                points[static_cast<std::size_t>(i)] = glm::vec3(
                        side * (0.26f + 0.10f * bulge),
                        0.10f + 0.48f * static_cast<float>(sc.cos),
                        0.08f + 0.62f * static_cast<float>(sc.sin));
                radii[static_cast<std::size_t>(i)] = 0.04f + 0.13f * bulge * bulge;
            }
            for (int i = 0; i < kSegments; ++i)
                mTubes.push_back(
                        {points[static_cast<std::size_t>(i)],
                         points[static_cast<std::size_t>(i + 1)],
                         radii[static_cast<std::size_t>(i)],
                         radii[static_cast<std::size_t>(i + 1)]});
            // The interventricular foramen into the third ventricle.
            mTubes.push_back(
                    {glm::vec3(side * 0.27f, 0.22f, 0.30f),
                     glm::vec3(0.0f, 0.12f, 0.22f),
                     0.05f,
                     0.05f});
            // Side branches off the C, seeded.
            for (int k = 0; k < 5; ++k) {
                const std::size_t at = 2 + rng.below(kSegments - 3);
                const glm::vec3 from = points[at];
                const glm::vec3 out(
                        side * rng.uniform(0.2f, 1.0f),
                        rng.uniform(-1.0f, 1.0f),
                        rng.uniform(-1.0f, 1.0f));
                const float length = rng.uniform(0.15f, 0.3f);
                mTubes.push_back(
                        {from,
                         from + out / std::sqrt(glm::dot(out, out)) * length,
                         rng.uniform(0.04f, 0.06f),
                         rng.uniform(0.02f, 0.035f)});
            }
        }
    }

    /** Negative inside the ventricles. */
    float operator()(const glm::vec3& p) const {
        float d = 1e9f;
        for (const Chamber& c : mChambers)
            d = smoothMin(d, chamberDistance(c, p), kBlend);
        for (const Tube& t : mTubes)
            d = smoothMin(d, tubeDistance(t, p), kBlend);
        return d;
    }

    glm::vec3 gradient(const glm::vec3& p, float step) const {
        const glm::vec3 g(
                (*this)(p + glm::vec3(step, 0.0f, 0.0f)) - (*this)(p - glm::vec3(step, 0.0f, 0.0f)),
                (*this)(p + glm::vec3(0.0f, step, 0.0f)) - (*this)(p - glm::vec3(0.0f, step, 0.0f)),
                (*this)(p + glm::vec3(0.0f, 0.0f, step)) -
                        (*this)(p - glm::vec3(0.0f, 0.0f, step)));
        const float length = std::sqrt(glm::dot(g, g));
        return length > 0.0f ? g / length : glm::vec3(0.0f);
    }

private:
    static constexpr float kBlend = 0.05f;
    std::vector<Chamber> mChambers;
    std::vector<Tube> mTubes;
};

/** Grid point (i, j, k) and the field there, for one cube being polygonised. */
struct Corner {
    glm::uvec3 index;
    float value;
};

class Extractor {
public:
    Extractor(const VentricleField& field, std::uint32_t cells, TriangleBatcher& out)
        : mField(field)
        , mCells(cells)
        , mStep(2.0f / static_cast<float>(cells))
        , mOut(out) {}

    Status run() {
        const std::size_t side = mCells + 1;
        std::vector<float> below(side * side);
        std::vector<float> above(side * side);
        sampleSlice(0, below);
        for (std::uint32_t k = 0; k < mCells; ++k) {
            sampleSlice(k + 1, above);
            for (std::uint32_t j = 0; j < mCells; ++j)
                for (std::uint32_t i = 0; i < mCells; ++i)
                    FF_RETURN_IF_ERROR(cube(i, j, k, below, above));
            std::swap(below, above);
        }
        return Status::ok();
    }

private:
    glm::vec3 fieldPoint(const glm::uvec3& index) const {
        return glm::vec3(index) * mStep - glm::vec3(1.0f);
    }

    void sampleSlice(std::uint32_t k, std::vector<float>& slice) const {
        const std::size_t side = mCells + 1;
        for (std::uint32_t j = 0; j <= mCells; ++j)
            for (std::uint32_t i = 0; i <= mCells; ++i)
                slice[j * side + i] = mField(fieldPoint(glm::uvec3(i, j, k)));
    }

    Status
    cube(std::uint32_t i,
         std::uint32_t j,
         std::uint32_t k,
         const std::vector<float>& below,
         const std::vector<float>& above) {
        const std::size_t side = mCells + 1;
        std::array<Corner, 8> corners{};
        bool anyInside = false;
        bool anyOutside = false;
        for (std::uint32_t c = 0; c < 8; ++c) {
            const glm::uvec3 index(i + (c & 1u), j + ((c >> 1) & 1u), k + ((c >> 2) & 1u));
            const std::vector<float>& slice = (c & 4u) ? above : below;
            const float value = slice[index.y * side + index.x];
            corners[c] = {index, value};
            (value < 0.0f ? anyInside : anyOutside) = true;
        }
        if (!anyInside || !anyOutside)
            return Status::ok();
        // Kuhn's six tetrahedra: 0 -> +a -> +a+b -> 7 for each order (a, b, c) of the axes.
        constexpr std::array<std::array<std::uint32_t, 2>, 6> kOrders = {
                {{1, 2}, {1, 4}, {2, 1}, {2, 4}, {4, 1}, {4, 2}}};
        for (const auto& [a, b] : kOrders) {
            const std::array<Corner, 4> tet = {corners[0], corners[a], corners[a | b], corners[7]};
            FF_RETURN_IF_ERROR(tetrahedron(tet));
        }
        return Status::ok();
    }

    Status tetrahedron(const std::array<Corner, 4>& tet) {
        std::array<int, 4> inside{};
        std::array<int, 4> outside{};
        int in = 0;
        int out = 0;
        for (int v = 0; v < 4; ++v) {
            if (tet[static_cast<std::size_t>(v)].value < 0.0f)
                inside[static_cast<std::size_t>(in++)] = v;
            else
                outside[static_cast<std::size_t>(out++)] = v;
        }
        if (in == 0 || out == 0)
            return Status::ok();
        glm::vec3 insideCentre(0.0f);
        glm::vec3 outsideCentre(0.0f);
        for (int v = 0; v < in; ++v)
            insideCentre += fieldPoint(
                    tet[static_cast<std::size_t>(inside[static_cast<std::size_t>(v)])].index);
        for (int v = 0; v < out; ++v)
            outsideCentre += fieldPoint(
                    tet[static_cast<std::size_t>(outside[static_cast<std::size_t>(v)])].index);
        const glm::vec3 outward =
                outsideCentre / static_cast<float>(out) - insideCentre / static_cast<float>(in);
        auto edge = [&](int p, int q) {
            return crossing(tet[static_cast<std::size_t>(p)], tet[static_cast<std::size_t>(q)]);
        };
        if (in == 1 || out == 1) {
            const int lone = in == 1 ? inside[0] : outside[0];
            const std::array<int, 4>& others = in == 1 ? outside : inside;
            return emit(
                    edge(lone, others[0]), edge(lone, others[1]), edge(lone, others[2]), outward);
        }
        const glm::vec3 ac = edge(inside[0], outside[0]);
        const glm::vec3 ad = edge(inside[0], outside[1]);
        const glm::vec3 bd = edge(inside[1], outside[1]);
        const glm::vec3 bc = edge(inside[1], outside[0]);
        FF_RETURN_IF_ERROR(emit(ac, ad, bd, outward));
        return emit(ac, bd, bc, outward);
    }

    /** Where the field crosses zero on the edge, computed from its lower-indexed end, so that
     *  the tetrahedra sharing the edge get the same point. */
    glm::vec3 crossing(Corner p, Corner q) const {
        const auto key = [](const glm::uvec3& v) {
            return std::array<std::uint32_t, 3>{v.z, v.y, v.x};
        };
        if (key(q.index) < key(p.index))
            std::swap(p, q);
        const float t = p.value / (p.value - q.value);
        const glm::vec3 a = fieldPoint(p.index);
        const glm::vec3 b = fieldPoint(q.index);
        return a + (b - a) * t;
    }

    Status emit(const glm::vec3& a, glm::vec3 b, glm::vec3 c, const glm::vec3& outward) {
        if (glm::dot(glm::cross(b - a, c - a), outward) < 0.0f)
            std::swap(b, c);
        return mOut.add(vertex(a), vertex(b), vertex(c));
    }

    SourceVertex vertex(const glm::vec3& p) const {
        SourceVertex v;
        v.position = p * kScale;
        v.normal = mField.gradient(p, 0.5f * mStep);
        // Pink tissue, a little darker towards the bottom.
        const float shade = 0.8f + 0.1f * (p.y + 1.0f);
        v.color = glm::vec4(0.80f * shade, 0.48f * shade, 0.45f * shade, 1.0f);
        return v;
    }

    const VentricleField& mField;
    std::uint32_t mCells;
    float mStep;
    TriangleBatcher& mOut;
};

Result<GeneratorReport> run(const GeneratorSpec& spec, ISceneSink& sink) {
    const ParamReader reader("isosurface", spec, kParams);
    FF_RETURN_IF_ERROR(reader.checkKnownKeys());
    FF_ASSIGN_OR_RETURN(const std::uint64_t resolution, reader.integer("resolution", 16, 1024));
    FF_ASSIGN_OR_RETURN(const std::uint64_t seed, reader.integer("seed", 0, ~0ull));
    const auto cells = static_cast<std::uint32_t>(resolution);

    FF_ASSIGN_OR_RETURN(const PrototypeId prototype, sink.addPrototype("ventricles"));
    VoxelGrid grid;
    grid.origin = glm::vec3(-kScale);
    grid.cellSize = 2.0f * kScale / static_cast<float>(cells);
    grid.cells = glm::uvec3(cells);
    FF_RETURN_IF_ERROR(sink.declareVoxelGrid(prototype, grid));

    const VentricleField field(seed);
    TriangleBatcher out(sink, prototype);
    FF_RETURN_IF_ERROR(Extractor(field, cells, out).run());
    FF_ASSIGN_OR_RETURN(GeneratorReport report, flushSingleMesh(out));
    FF_RETURN_IF_ERROR(sink.addInstance(prototype, glm::dmat4(1.0)));
    return report;
}

} // namespace

GeneratorEntry isosurfaceGenerator() {
    return {makeGeneratorInfo(
                    "isosurface",
                    "a ventricle-like system of chambers and tubes, the zero set of a procedural "
                    "volume "
                    "extracted by marching tetrahedra on a regular grid (Meißner et al.'s "
                    "ventricles; for ORSD)",
                    kParams),
            run};
}

} // namespace ff::builder::generators
