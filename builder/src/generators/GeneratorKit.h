#pragma once

// What every procedural generator shares: a portable RNG and hash, libm-free trigonometry,
// parameter reading against a declared table, and a batching emitter into the ISceneSink.
//
// Determinism contract (Generators.h: same spec -> same triangles on every machine): generators
// use only IEEE-754 +, -, *, /, sqrt and floor, which are correctly rounded everywhere, plus the
// integer RNG below. std::sin/std::cos (libm-dependent) and std::uniform_*_distribution
// (implementation-defined) are deliberately not used. The generator sources are compiled with
// -ffp-contract=off so that no compiler fuses a*b+c into an FMA on one machine but not another.

#include <ff/builder/Generators.h>
#include <ff/builder/SceneSink.h>
#include <ff/storage/SceneFormat.h>
#include <ff/storage/Status.h>

#include <glm/glm.hpp>

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace ff::builder::generators {

// ---------------------------------------------------------------------------------------------
// Random numbers and hashing

/** SplitMix64 (Steele, Lea, Flood 2014): 64-bit state, passes BigCrush, trivially portable. */
class SplitMix64 {
public:
    explicit SplitMix64(std::uint64_t seed) noexcept
        : mState(seed) {}

    std::uint64_t next() noexcept {
        std::uint64_t z = (mState += 0x9E3779B97F4A7C15ull);
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        return z ^ (z >> 31);
    }

    /** Uniform in [0, 1), exactly representable (24 random bits). */
    float unit() noexcept { return static_cast<float>(next() >> 40) * 0x1.0p-24f; }

    /** Uniform in [lo, hi). */
    float uniform(float lo, float hi) noexcept { return lo + (hi - lo) * unit(); }

    /** Uniform integer in [0, n), n > 0 (multiply-high: no modulo bias worth mentioning). */
    std::uint32_t below(std::uint32_t n) noexcept {
        return static_cast<std::uint32_t>(((next() >> 32) * n) >> 32);
    }

private:
    std::uint64_t mState;
};

/** The SplitMix64 finaliser: a bijective 64-bit mix, used to hash lattice points and streams. */
constexpr std::uint64_t mix64(std::uint64_t z) noexcept {
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

/** An independent RNG stream per purpose, so that e.g. the forest layout does not shift when
 *  the tree's shape code draws one more number. */
constexpr std::uint64_t streamSeed(std::uint64_t seed, std::uint64_t stream) noexcept {
    return mix64(seed ^ mix64(stream + 0x632BE59BD9B4E019ull));
}

// ---------------------------------------------------------------------------------------------
// Trigonometry without libm

struct SinCos {
    double sin;
    double cos;
};

/**
 * sin and cos of an angle given in turns (1 turn = 360 degrees). Range reduction to the nearest
 * quarter turn, then Taylor polynomials on [-pi/4, pi/4] (error < 1e-15): only + - * and floor,
 * so the result is bit-identical on every IEEE-754 machine, unlike std::sin.
 */
SinCos sinCosTurns(double turns) noexcept;

// ---------------------------------------------------------------------------------------------
// Parameters

/** One parameter of a generator: the single source of its default, range text and help. */
struct ParamDef {
    std::string_view key;
    std::string_view defaultValue; ///< parsed exactly like user input
    std::string_view meaning;
};

/** Builds the catalog entry ("key", "default: meaning") from a generator's parameter table. */
GeneratorInfo makeGeneratorInfo(
        std::string_view name, std::string_view summary, std::span<const ParamDef> params);

/**
 * Reads a spec's parameters against a table of ParamDefs. Every error is InvalidArgument and
 * names the generator and the key: "forest: parameter 'trees': must be a power of 4, got 3".
 */
class ParamReader {
public:
    ParamReader(
            std::string_view generator,
            const GeneratorSpec& spec,
            std::span<const ParamDef> defs) noexcept
        : mGenerator(generator)
        , mSpec(spec)
        , mDefs(defs) {}

    /** Fails on the first key that the table does not declare. */
    [[nodiscard]] Status checkKnownKeys() const;

    /** A base-10 unsigned integer in [min, max]; the default when the key is absent. */
    [[nodiscard]] Result<std::uint64_t>
    integer(std::string_view key, std::uint64_t min, std::uint64_t max) const;

    /** A finite decimal number in [min, max]. */
    [[nodiscard]] Result<double> real(std::string_view key, double min, double max) const;

    /** An InvalidArgument Status naming the generator and `key`. */
    [[nodiscard]] Status invalid(std::string_view key, std::string_view why) const;

private:
    std::string_view text(std::string_view key) const;

    std::string_view mGenerator;
    const GeneratorSpec& mSpec;
    std::span<const ParamDef> mDefs;
};

// ---------------------------------------------------------------------------------------------
// Emitting triangles

/** Triangles per addTriangles call: 4096 x 60 B = 240 KiB, large enough to amortise the call,
 *  small enough to stay in L2 and to keep a generator's memory independent of the scene. */
inline constexpr std::size_t kBatchTriangles = 4096;

/**
 * Collects triangles for one prototype and hands them to the sink kBatchTriangles at a time.
 * Call flush() once at the end; the destructor does not (it could not report an error).
 */
class TriangleBatcher {
public:
    TriangleBatcher(ISceneSink& sink, PrototypeId prototype);
    TriangleBatcher(const TriangleBatcher&) = delete;
    TriangleBatcher& operator=(const TriangleBatcher&) = delete;

    [[nodiscard]] Status add(const SourceVertex& a, const SourceVertex& b, const SourceVertex& c) {
        return add(packTriangle(a, b, c));
    }

    [[nodiscard]] Status add(const storage::PackedTriangle& triangle) {
        mBatch.push_back(triangle);
        return mBatch.size() < kBatchTriangles ? Status::ok() : flush();
    }

    /** Sends the pending triangles, if any. */
    [[nodiscard]] Status flush();

    /** Triangles added so far (sent or pending). */
    std::uint64_t added() const noexcept { return mSent + mBatch.size(); }

private:
    ISceneSink& mSink;
    PrototypeId mPrototype;
    std::vector<storage::PackedTriangle> mBatch;
    std::uint64_t mSent = 0;
};

/** An oriented box: centre, orthonormal right-handed axes, half extents. */
struct Box {
    glm::vec3 center;
    std::array<glm::vec3, 3> axis;
    std::array<float, 3> half;
};

/** An axis-aligned box from its corners. */
Box axisBox(const glm::vec3& lo, const glm::vec3& hi) noexcept;

/** A box's six outward-facing faces, each a grid of segments[u] x segments[v] quads of two
 *  triangles (u, v the face's two other axes), flat normals: 4 (xy + yz + zx) triangles. */
[[nodiscard]] Status emitBox(
        const Box& box,
        const std::array<std::uint32_t, 3>& segments,
        const glm::vec4& color,
        TriangleBatcher& out);

/** Flushes `out` and reports a scene of that one prototype drawn once (the terrain, the blinds,
 *  the sphere); the caller adds its instance. */
[[nodiscard]] Result<GeneratorReport> flushSingleMesh(TriangleBatcher& out);

/** Column-major affine transform: translate(t) * rotateY(turns) * scale(s). */
glm::mat4 makeTransform(const glm::vec3& translation, double yawTurns, float scale) noexcept;

// ---------------------------------------------------------------------------------------------
// The generators, one file each (dispatched from Generators.cpp)

struct GeneratorEntry {
    GeneratorInfo info;
    Result<GeneratorReport> (*run)(const GeneratorSpec& spec, ISceneSink& sink);
};

GeneratorEntry forestGenerator();
GeneratorEntry terrainGenerator();
GeneratorEntry moleculeGenerator();
GeneratorEntry blindsGenerator();
GeneratorEntry sphereGenerator();
GeneratorEntry cityGenerator();
GeneratorEntry cathedralGenerator();
GeneratorEntry isosurfaceGenerator();

} // namespace ff::builder::generators
