// molecule: a protein-like blob of atoms, after the tumor necrosis factor molecule of
// Chamberlain et al. '96 (Table 1: 6,534 spheres, 5,227,200 triangles = 800 per sphere).
// One unit-sphere prototype per element, each atom an instance scaled by its radius — the
// compact-by-instancing case that the paper's octree could not exploit.
//
// Atoms follow a semi-stiff random walk (a backbone) held together by a weak pull toward the
// centre, which folds the chain into a compact globule instead of a sqrt(N)-sized coil.

#include "GeneratorKit.h"

#include <array>
#include <cmath>

namespace ff::builder::generators {

namespace {

constexpr std::array<ParamDef, 3> kParams = {{
        {"spheres", "6534", "number of atoms (1..100000000); 6534 is the paper's molecule"},
        {"seed", "1", "random seed for the chain and the element sequence"},
        {"triangles_per_sphere", "800", "target triangles per sphere prototype (12..200000)"},
}};

struct Element {
    const char* name;
    float radius;    ///< van der Waals radius, angstrom (= scene units)
    glm::vec4 color; ///< CPK convention, linear RGB
    float share;     ///< fraction of atoms, roughly a protein with explicit hydrogens
};

constexpr std::array<Element, 5> kElements = {{
        {"atom-C", 1.70f, {0.10f, 0.10f, 0.10f, 1.0f}, 0.36f},
        {"atom-H", 1.20f, {0.90f, 0.90f, 0.90f, 1.0f}, 0.36f},
        {"atom-N", 1.55f, {0.08f, 0.15f, 0.90f, 1.0f}, 0.11f},
        {"atom-O", 1.52f, {0.85f, 0.04f, 0.02f, 1.0f}, 0.15f},
        {"atom-S", 1.80f, {0.90f, 0.75f, 0.05f, 1.0f}, 0.02f},
}};

/** Bonded atoms overlap as in a space-filling model: centres this fraction of the radius sum. */
constexpr float kBondFactor = 0.6f;
/** Tendency of the chain to keep its direction (0 = pure random walk). */
constexpr float kStiffness = 0.6f;

std::size_t pickElement(SplitMix64& rng) noexcept {
    const float u = rng.unit();
    float cumulative = 0.0f;
    for (std::size_t e = 0; e + 1 < kElements.size(); ++e) {
        cumulative += kElements[e].share;
        if (u < cumulative)
            return e;
    }
    return kElements.size() - 1;
}

glm::vec3 randomUnitVector(SplitMix64& rng) noexcept {
    const float z = rng.uniform(-1.0f, 1.0f);
    const SinCos azimuth = sinCosTurns(static_cast<double>(rng.unit()));
    const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
    return {r * static_cast<float>(azimuth.cos), r * static_cast<float>(azimuth.sin), z};
}

/** Cube root by bisection: only * and comparisons, so, unlike std::cbrt (libm), the same on
 *  every machine. x >= 0. */
double cubeRoot(double x) noexcept {
    double lo = 0.0;
    double hi = std::max(1.0, x);
    for (int i = 0; i < 64; ++i) {
        const double mid = 0.5 * (lo + hi);
        (mid * mid * mid < x ? lo : hi) = mid;
    }
    return hi;
}

/** Slices x stacks of a UV sphere giving 2 * slices * (stacks - 1) triangles near `target`. */
struct SphereTessellation {
    std::uint32_t slices;
    std::uint32_t stacks;
    std::uint64_t triangles() const noexcept { return 2ull * slices * (stacks - 1); }
};

SphereTessellation chooseTessellation(std::uint64_t target) noexcept {
    const auto slices = std::max<std::uint32_t>(
            3,
            static_cast<std::uint32_t>(std::lround(std::sqrt(static_cast<double>(target) / 2.0))));
    const auto bands = std::max<std::uint32_t>(
            2,
            static_cast<std::uint32_t>(std::lround(static_cast<double>(target) / (2.0 * slices))));
    return {slices, bands + 1};
}

/** A unit sphere centred at the origin; poles on Y; outward counter-clockwise winding. */
Status emitSphere(const SphereTessellation& t, const glm::vec4& color, TriangleBatcher& out) {
    auto vertex = [&](std::uint32_t stack, std::uint32_t slice) {
        const SinCos polar = sinCosTurns(0.5 * stack / t.stacks);
        const SinCos azimuth = sinCosTurns(static_cast<double>(slice) / t.slices);
        const glm::vec3 p(
                static_cast<float>(polar.sin * azimuth.cos),
                static_cast<float>(polar.cos),
                static_cast<float>(polar.sin * azimuth.sin));
        return SourceVertex{p, p, color};
    };
    for (std::uint32_t stack = 0; stack < t.stacks; ++stack) {
        for (std::uint32_t slice = 0; slice < t.slices; ++slice) {
            const SourceVertex a = vertex(stack, slice);
            const SourceVertex b = vertex(stack + 1, slice);
            const SourceVertex c = vertex(stack + 1, slice + 1);
            const SourceVertex d = vertex(stack, slice + 1);
            // The polar bands are fans: there a and d (north) or b and c (south) coincide.
            if (stack == 0) {
                FF_RETURN_IF_ERROR(out.add(a, c, b));
            } else if (stack + 1 == t.stacks) {
                FF_RETURN_IF_ERROR(out.add(a, d, b));
            } else {
                FF_RETURN_IF_ERROR(out.add(a, d, b));
                FF_RETURN_IF_ERROR(out.add(d, c, b));
            }
        }
    }
    return Status::ok();
}

/**
 * Replays the chain: calls `visit(element, centre)` for each atom in order. Reseeding from the
 * spec makes a second pass identical to the first without storing anything.
 */
template <typename Visit> Status walkChain(std::uint64_t seed, std::uint64_t atoms, Visit&& visit) {
    SplitMix64 elementRng(streamSeed(seed, 1));
    SplitMix64 stepRng(streamSeed(seed, 2));
    // Radius of a globule packing the atoms at ~50% density: where the pull starts to matter.
    const float meanRadius = 1.5f;
    const auto globule = static_cast<float>(
            meanRadius * kBondFactor * 2.0 * cubeRoot(static_cast<double>(atoms) / 0.5));
    glm::vec3 position(0.0f);
    glm::vec3 direction = randomUnitVector(stepRng);
    std::size_t element = pickElement(elementRng);
    for (std::uint64_t k = 0; k < atoms; ++k) {
        FF_RETURN_IF_ERROR(visit(element, position));
        const std::size_t next = pickElement(elementRng);
        const glm::vec3 pull = position * (-1.0f / globule);
        direction = glm::normalize(kStiffness * direction + randomUnitVector(stepRng) + pull);
        position +=
                direction * (kBondFactor * (kElements[element].radius + kElements[next].radius));
        element = next;
    }
    return Status::ok();
}

Result<GeneratorReport> runMolecule(const GeneratorSpec& spec, ISceneSink& sink) {
    const ParamReader reader("molecule", spec, kParams);
    FF_RETURN_IF_ERROR(reader.checkKnownKeys());
    FF_ASSIGN_OR_RETURN(const std::uint64_t atoms, reader.integer("spheres", 1, 100'000'000));
    FF_ASSIGN_OR_RETURN(const std::uint64_t seed, reader.integer("seed", 0, ~0ull));
    FF_ASSIGN_OR_RETURN(
            const std::uint64_t target, reader.integer("triangles_per_sphere", 12, 200'000));
    const SphereTessellation tessellation = chooseTessellation(target);

    // Pass 1: which elements occur (small molecules need not store all five spheres).
    std::array<std::uint64_t, kElements.size()> counts{};
    FF_RETURN_IF_ERROR(walkChain(seed, atoms, [&](std::size_t element, const glm::vec3&) {
        ++counts[element];
        return Status::ok();
    }));

    GeneratorReport report;
    std::array<PrototypeId, kElements.size()> prototypes{};
    for (std::size_t e = 0; e < kElements.size(); ++e) {
        if (counts[e] == 0)
            continue;
        FF_ASSIGN_OR_RETURN(prototypes[e], sink.addPrototype(kElements[e].name));
        TriangleBatcher out(sink, prototypes[e]);
        FF_RETURN_IF_ERROR(emitSphere(tessellation, kElements[e].color, out));
        FF_RETURN_IF_ERROR(out.flush());
        report.storedTriangles += out.added();
        report.triangles += out.added() * counts[e];
        ++report.prototypes;
    }

    // Pass 2: the same chain again, now placing instances.
    FF_RETURN_IF_ERROR(walkChain(seed, atoms, [&](std::size_t element, const glm::vec3& centre) {
        return sink.addInstance(
                prototypes[element], glm::dmat4(makeTransform(centre, 0.0, kElements[element].radius)));
    }));
    report.instances = atoms;
    return report;
}

} // namespace

GeneratorEntry moleculeGenerator() {
    return {makeGeneratorInfo(
                    "molecule",
                    "a compact protein-like cluster of CPK-coloured atoms: one sphere prototype "
                    "per element, one instance per atom",
                    kParams),
            &runMolecule};
}

} // namespace ff::builder::generators
