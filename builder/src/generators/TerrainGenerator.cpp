// terrain: a flat, non-instanced, coloured heightfield — the opposite of the forest: no
// instancing to exploit, every triangle stored. Stands in for the island's 33,000-polygon ground
// (Chamberlain et al. '96, §5) and scales to 10^9+ triangles for out-of-core builds.
//
// Streams one grid row at a time: two rows of packed vertices are the only per-scene memory
// (O(sqrt N)); each vertex is evaluated and packed once and shared by its six triangles.

#include "GeneratorKit.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <vector>

namespace ff::builder::generators {

namespace {

constexpr std::array<ParamDef, 2> kParams = {{
        {"triangles", "1000000", "at least this many triangles, 2 per grid cell (1..10^12)"},
        {"seed", "1", "random seed for the height noise"},
}};

constexpr std::uint64_t kMaxTriangles = 1'000'000'000'000ull;
constexpr double kCellSize = 1.0; // units: triangles stay ~1 unit whatever the count

/** Fractal value noise: a few octaves, gentle enough for grass on most slopes. */
struct Octave {
    double wavelength; ///< units between lattice points
    double amplitude;  ///< units of height
};
constexpr std::array<Octave, 6> kOctaves = {{
        {512.0, 40.0},
        {192.0, 14.0},
        {72.0, 5.0},
        {27.0, 1.6},
        {10.0, 0.45},
        {4.0, 0.1},
}};

struct GridSize {
    std::uint64_t columns; ///< cells along X
    std::uint64_t rows;    ///< cells along Z
};

/** Cells >= ceil(N/2) with the least excess, near-square (searching widths around sqrt). */
GridSize chooseGrid(std::uint64_t triangles) {
    const std::uint64_t cells = (triangles + 1) / 2;
    auto root = static_cast<std::uint64_t>(std::sqrt(static_cast<double>(cells)));
    while (root * root > cells)
        --root;
    while ((root + 1) * (root + 1) <= cells)
        ++root;
    constexpr std::uint64_t kSearch = 256; // widths tried on each side of sqrt(cells)
    GridSize best{1, cells};
    std::uint64_t bestExcess = ~0ull;
    for (std::uint64_t w = (root > kSearch ? root - kSearch : 1); w <= root + kSearch; ++w) {
        const std::uint64_t h = (cells + w - 1) / w;
        const std::uint64_t excess = w * h - cells;
        const std::uint64_t skew = std::max(w, h) - std::min(w, h);
        const std::uint64_t bestSkew =
                std::max(best.columns, best.rows) - std::min(best.columns, best.rows);
        if (excess < bestExcess || (excess == bestExcess && skew < bestSkew)) {
            best = {w, h};
            bestExcess = excess;
        }
    }
    return best;
}

/** Quintic fade 6t^5 - 15t^4 + 10t^3 and its derivative: C2, so normals are smooth. */
double fade(double t) noexcept {
    return t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
}
double fadeDerivative(double t) noexcept {
    return 30.0 * t * t * (t * (t - 2.0) + 1.0);
}

struct HeightSample {
    double height;
    double dx; ///< dheight/dx
    double dz; ///< dheight/dz
};

/**
 * Evaluates the noise along one row of constant z, for increasing x. Caches each octave's four
 * lattice values until x crosses into the next lattice cell, so most vertices hash nothing.
 */
class RowNoise {
public:
    RowNoise(std::uint64_t seed, double z) noexcept {
        for (std::size_t o = 0; o < kOctaves.size(); ++o) {
            OctaveState& s = mState[o];
            s.seed = streamSeed(seed, o);
            const double fz = z / kOctaves[o].wavelength;
            const double j = std::floor(fz);
            s.j = static_cast<std::int64_t>(j);
            s.v = fade(fz - j);
            s.dv = fadeDerivative(fz - j) / kOctaves[o].wavelength;
        }
    }

    HeightSample sample(double x) noexcept {
        HeightSample out{0.0, 0.0, 0.0};
        for (std::size_t o = 0; o < kOctaves.size(); ++o) {
            OctaveState& s = mState[o];
            const double fx = x / kOctaves[o].wavelength;
            const double i = std::floor(fx);
            const auto cell = static_cast<std::int64_t>(i);
            if (!s.valid || cell != s.i) {
                s.i = cell;
                s.valid = true;
                s.a = lattice(s.seed, cell, s.j);
                s.b = lattice(s.seed, cell + 1, s.j);
                s.c = lattice(s.seed, cell, s.j + 1);
                s.d = lattice(s.seed, cell + 1, s.j + 1);
            }
            const double u = fade(fx - i);
            const double du = fadeDerivative(fx - i) / kOctaves[o].wavelength;
            const double k = s.a - s.b - s.c + s.d;
            const double amplitude = kOctaves[o].amplitude;
            out.height += amplitude * (s.a + (s.b - s.a) * u + (s.c - s.a) * s.v + k * u * s.v);
            out.dx += amplitude * ((s.b - s.a) + k * s.v) * du;
            out.dz += amplitude * ((s.c - s.a) + k * u) * s.dv;
        }
        return out;
    }

private:
    /** Hash of a lattice point to [-1, 1). Integer-only, so identical on every machine. */
    static double lattice(std::uint64_t seed, std::int64_t i, std::int64_t j) noexcept {
        const std::uint64_t h =
                mix64(mix64(seed ^ static_cast<std::uint64_t>(i)) ^
                      (static_cast<std::uint64_t>(j) * 0xC2B2AE3D27D4EB4Full));
        return static_cast<double>(h >> 11) * 0x1.0p-52 - 1.0;
    }

    struct OctaveState {
        std::uint64_t seed = 0;
        std::int64_t i = 0;
        std::int64_t j = 0;
        bool valid = false;
        double v = 0.0, dv = 0.0;
        double a = 0.0, b = 0.0, c = 0.0, d = 0.0;
    };
    std::array<OctaveState, kOctaves.size()> mState{};
};

glm::vec3 mix(const glm::vec3& a, const glm::vec3& b, double t) noexcept {
    return a + (b - a) * static_cast<float>(t);
}

/** Linear RGB by height band, pushed toward bare rock on steep slopes. */
glm::vec4 terrainColor(const HeightSample& s) noexcept {
    struct Stop {
        double t;
        glm::vec3 color;
    };
    static constexpr std::array<Stop, 6> kStops = {{
            {-0.60, {0.10f, 0.08f, 0.04f}}, // mud
            {-0.25, {0.05f, 0.15f, 0.03f}}, // lush grass
            {0.15, {0.11f, 0.16f, 0.04f}},  // dry grass
            {0.40, {0.16f, 0.11f, 0.05f}},  // earth
            {0.60, {0.22f, 0.21f, 0.19f}},  // rock
            {0.75, {0.80f, 0.82f, 0.86f}},  // snow
    }};
    static constexpr glm::vec3 kRock = {0.20f, 0.19f, 0.18f};
    constexpr double kHeightScale = 30.0; // typical |height| of the octave sum

    const double t = s.height / kHeightScale;
    glm::vec3 color = kStops.front().color;
    if (t >= kStops.back().t) {
        color = kStops.back().color;
    } else {
        for (std::size_t k = 1; k < kStops.size(); ++k) {
            if (t < kStops[k].t) {
                const double f =
                        std::max(0.0, (t - kStops[k - 1].t) / (kStops[k].t - kStops[k - 1].t));
                color = mix(kStops[k - 1].color, kStops[k].color, f);
                break;
            }
        }
    }
    const double slope = std::sqrt(s.dx * s.dx + s.dz * s.dz);
    const double rockiness = std::clamp((slope - 0.45) / 0.35, 0.0, 1.0);
    return glm::vec4(mix(color, kRock, rockiness), 1.0f);
}

/** Evaluates and packs the W+1 vertices of grid line `row`. */
void fillRow(
        std::uint64_t seed,
        const GridSize& grid,
        std::uint64_t row,
        std::vector<storage::PackedVertex>& out) {
    // Centred on the origin; x along columns, z along rows, Y up.
    const double x0 = -0.5 * static_cast<double>(grid.columns) * kCellSize;
    const double z = (static_cast<double>(row) - 0.5 * static_cast<double>(grid.rows)) * kCellSize;
    RowNoise noise(seed, z);
    for (std::size_t col = 0; col < out.size(); ++col) {
        const double x = x0 + static_cast<double>(col) * kCellSize;
        const HeightSample s = noise.sample(x);
        SourceVertex v;
        v.position = glm::vec3(
                static_cast<float>(x), static_cast<float>(s.height), static_cast<float>(z));
        v.normal = glm::normalize(
                glm::vec3(static_cast<float>(-s.dx), 1.0f, static_cast<float>(-s.dz)));
        v.color = terrainColor(s);
        out[col] = packVertex(v, v.normal); // the gradient normal is always usable
    }
}

Result<GeneratorReport> runTerrain(const GeneratorSpec& spec, ISceneSink& sink) {
    const ParamReader reader("terrain", spec, kParams);
    FF_RETURN_IF_ERROR(reader.checkKnownKeys());
    FF_ASSIGN_OR_RETURN(
            const std::uint64_t requested, reader.integer("triangles", 1, kMaxTriangles));
    FF_ASSIGN_OR_RETURN(const std::uint64_t seed, reader.integer("seed", 0, ~0ull));

    const GridSize grid = chooseGrid(requested);
    FF_ASSIGN_OR_RETURN(const PrototypeId prototype, sink.addPrototype("terrain"));
    // Declared first so a consumer knows the placement before the (possibly huge) stream.
    FF_RETURN_IF_ERROR(sink.addInstance(prototype, glm::dmat4(1.0)));

    std::vector<storage::PackedVertex> below(grid.columns + 1);
    std::vector<storage::PackedVertex> above(grid.columns + 1);
    fillRow(seed, grid, 0, below);
    TriangleBatcher out(sink, prototype);
    for (std::uint64_t row = 0; row < grid.rows; ++row) {
        fillRow(seed, grid, row + 1, above);
        for (std::size_t col = 0; col < grid.columns; ++col) {
            // Counter-clockwise seen from +Y.
            FF_RETURN_IF_ERROR(out.add({{below[col], above[col], below[col + 1]}}));
            FF_RETURN_IF_ERROR(out.add({{below[col + 1], above[col], above[col + 1]}}));
        }
        std::swap(below, above);
    }
    FF_ASSIGN_OR_RETURN(const GeneratorReport report, flushSingleMesh(out));
    FF_ASSERT(report.storedTriangles == 2 * grid.columns * grid.rows);
    return report;
}

} // namespace

GeneratorEntry terrainGenerator() {
    return {makeGeneratorInfo(
                    "terrain",
                    "a flat (non-instanced) coloured fractal heightfield, ~1-unit triangles, "
                    "streamed row by row",
                    kParams),
            &runTerrain};
}

} // namespace ff::builder::generators
