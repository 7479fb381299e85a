// forest: the recursively instanced tree scenes of Chamberlain et al. '96 (§5.2, Plate 5,
// Figure 5): one ~52k-triangle tree (their Plate 1 tree has 52,470) planted N = 4^k times in a
// recursive 2x2 layout, up to 16,384 trees (861.6 M triangles drawn). The tree is stored once; each
// tree is an instance (one transform), so N trees cost one tree plus N transforms.
//
// The tree is a fixed branching skeleton (trunk -> limbs -> branches -> shoots -> twigs) of
// tapered, slightly bent tubes with folded leaves on the twigs. The seed moves branch angles,
// lengths and colours, never the counts, so every seed gives exactly kTreeTriangles.

#include "GeneratorKit.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace ff::builder::generators {

namespace {

constexpr std::array<ParamDef, 2> kParams = {{
        {"trees", "16", "number of trees, a power of 4 (1, 4, 16, ..., 16384, ..., 4^12)"},
        {"seed", "1", "random seed for the tree's shape and each tree's yaw and scale"},
}};

constexpr std::uint64_t kMaxTrees = 1ull << 24; // 4^12

/** One level of the branching skeleton; level 0 is the trunk. */
struct LimbLevel {
    std::uint32_t children; ///< limbs of the next level grown from each limb of this one
    std::uint32_t sides;    ///< polygon sides of the tube
    std::uint32_t segments; ///< rings - 1 along the tube
    std::uint32_t leaves;   ///< leaves on each limb of this level
};
constexpr std::array<LimbLevel, 5> kLevels = {{
        {7, 10, 10, 0}, // trunk
        {5, 7, 6, 0},   // limbs
        {4, 5, 4, 0},   // branches
        {3, 4, 3, 0},   // shoots
        {0, 3, 2, 25},  // twigs, carrying the leaves
}};
constexpr std::uint32_t kMaxSides = 10;
constexpr std::uint32_t kMaxSegments = 10;
constexpr std::uint32_t kMaxChildren = 7;
constexpr std::uint64_t kTrianglesPerLeaf = 4;

constexpr std::uint64_t treeTriangles() {
    std::uint64_t limbs = 1;
    std::uint64_t total = 0;
    for (const LimbLevel& level : kLevels) {
        total += limbs * (2ull * level.sides * level.segments + level.leaves * kTrianglesPerLeaf);
        limbs *= level.children;
    }
    return total;
}
constexpr std::uint64_t kTreeTriangles = treeTriangles();
// 52,588: 10,588 in 603 tubes + 42,000 in 10,500 leaves (the paper's tree: 52,470).
static_assert(kTreeTriangles >= 45'000 && kTreeTriangles <= 55'000);
static_assert(kLevels.back().children == 0);

// Shape, in units; the tree stands ~10 tall on the origin, Y up.
constexpr float kTrunkLength = 7.0f;
constexpr float kTrunkRadius = 0.45f;
constexpr float kLeafLength = 0.45f;
constexpr glm::vec3 kUp(0.0f, 1.0f, 0.0f);

constexpr glm::vec4 kBark(0.10f, 0.06f, 0.03f, 1.0f); // linear RGB

/** Centre and frame of one ring of a tube. */
struct Ring {
    glm::vec3 center;
    glm::vec3 direction; ///< unit tangent of the axis
    glm::vec3 u, v;      ///< unit, perpendicular: u x v = direction
    float radius;
};

struct Limb {
    std::uint32_t level;
    glm::vec3 base;
    glm::vec3 direction; ///< unit
    glm::vec3 hint;      ///< any vector not parallel to direction: orients the ring frames
    float length;
    float baseRadius;
    float tipRadius;
};

/** A unit vector perpendicular to `direction`, as close to `hint` as possible. */
glm::vec3 perpendicular(const glm::vec3& direction, const glm::vec3& hint) noexcept {
    glm::vec3 p = hint - glm::dot(hint, direction) * direction;
    if (glm::dot(p, p) < 1e-6f) {
        const glm::vec3 axis =
                std::fabs(direction.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 0, 1);
        p = axis - glm::dot(axis, direction) * direction;
    }
    return glm::normalize(p);
}

glm::vec3 randomUnitVector(SplitMix64& rng) noexcept {
    const float z = rng.uniform(-1.0f, 1.0f);
    const SinCos azimuth = sinCosTurns(static_cast<double>(rng.unit()));
    const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
    return {r * static_cast<float>(azimuth.cos), r * static_cast<float>(azimuth.sin), z};
}

/** cos(turns) * a + sin(turns) * b */
glm::vec3 rotateIn(const glm::vec3& a, const glm::vec3& b, double turns) noexcept {
    const SinCos r = sinCosTurns(turns);
    return static_cast<float>(r.cos) * a + static_cast<float>(r.sin) * b;
}

/** Emits the tree and measures it: the forest's spacing needs the crown's radius. */
class TreeEmitter {
public:
    TreeEmitter(ISceneSink& sink, PrototypeId prototype, std::uint64_t seed)
        : mOut(sink, prototype)
        , mRng(streamSeed(seed, 1)) {}

    Status grow() {
        Limb trunk{};
        trunk.level = 0;
        trunk.base = glm::vec3(0.0f, -0.2f, 0.0f); // roots a little below the ground plane
        const glm::vec3 lean(mRng.uniform(-0.06f, 0.06f), 0.0f, mRng.uniform(-0.06f, 0.06f));
        trunk.direction = glm::normalize(kUp + lean);
        trunk.hint = glm::vec3(1.0f, 0.0f, 0.0f);
        trunk.length = kTrunkLength;
        trunk.baseRadius = kTrunkRadius;
        trunk.tipRadius = 0.35f * kTrunkRadius;
        FF_RETURN_IF_ERROR(growLimb(trunk));
        return mOut.flush();
    }

    std::uint64_t triangles() const noexcept { return mOut.added(); }
    /** Largest distance of a vertex from the vertical axis through the origin. */
    float crownRadius() const noexcept { return std::sqrt(mMaxRadial2); }

private:
    Status add(const SourceVertex& a, const SourceVertex& b, const SourceVertex& c) {
        for (const SourceVertex* v : {&a, &b, &c})
            mMaxRadial2 = std::max(
                    mMaxRadial2, v->position.x * v->position.x + v->position.z * v->position.z);
        return mOut.add(a, b, c);
    }

    Status growLimb(const Limb& limb) {
        const LimbLevel& level = kLevels[limb.level];
        FF_ASSERT(level.sides <= kMaxSides && level.segments <= kMaxSegments);

        // Axis: bends upward (thin limbs reach for light) with a little wobble.
        const float upBend = limb.level == 0 ? 0.0f : 0.05f * static_cast<float>(limb.level);
        std::array<Ring, kMaxSegments + 1> rings{};
        glm::vec3 center = limb.base;
        glm::vec3 direction = limb.direction;
        const float step = limb.length / static_cast<float>(level.segments);
        for (std::uint32_t k = 0; k <= level.segments; ++k) {
            const float t = static_cast<float>(k) / static_cast<float>(level.segments);
            Ring& ring = rings[k];
            ring.center = center;
            ring.direction = direction;
            ring.u = perpendicular(direction, k == 0 ? limb.hint : rings[k - 1].u);
            ring.v = glm::cross(direction, ring.u);
            ring.radius = limb.baseRadius + (limb.tipRadius - limb.baseRadius) * t;
            center += direction * step;
            const glm::vec3 wobble(
                    mRng.uniform(-0.08f, 0.08f),
                    mRng.uniform(-0.08f, 0.08f),
                    mRng.uniform(-0.08f, 0.08f));
            direction = glm::normalize(direction + upBend * kUp + wobble);
        }

        // Bark: one shade per limb.
        const float shade = mRng.uniform(0.8f, 1.2f);
        const glm::vec4 bark(glm::vec3(kBark) * shade, 1.0f);
        FF_RETURN_IF_ERROR(emitTube(rings, level, bark));

        for (std::uint32_t i = 0; i < level.leaves; ++i)
            FF_RETURN_IF_ERROR(emitLeaf(rings, level, i));

        // Children: decided first (they need this limb's rings), then grown depth-first.
        std::array<Limb, kMaxChildren> children{};
        FF_ASSERT(level.children <= kMaxChildren);
        const double firstAzimuth = mRng.unit();
        for (std::uint32_t i = 0; i < level.children; ++i)
            children[i] = planChild(limb, rings, level, i, firstAzimuth);
        for (std::uint32_t i = 0; i < level.children; ++i)
            FF_RETURN_IF_ERROR(growLimb(children[i]));
        return Status::ok();
    }

    /** The ring frame at fraction s in [0, 1] of the limb, interpolated between rings. */
    static Ring
    ringAt(const std::array<Ring, kMaxSegments + 1>& rings, const LimbLevel& level, float s) {
        const float x = s * static_cast<float>(level.segments);
        const auto k = std::min(static_cast<std::uint32_t>(x), level.segments - 1);
        const float f = x - static_cast<float>(k);
        const Ring& a = rings[k];
        const Ring& b = rings[k + 1];
        Ring r;
        r.center = a.center + (b.center - a.center) * f;
        r.direction = glm::normalize(a.direction + (b.direction - a.direction) * f);
        r.u = perpendicular(r.direction, a.u);
        r.v = glm::cross(r.direction, r.u);
        r.radius = a.radius + (b.radius - a.radius) * f;
        return r;
    }

    Limb planChild(
            const Limb& parent,
            const std::array<Ring, kMaxSegments + 1>& rings,
            const LimbLevel& level,
            std::uint32_t index,
            double firstAzimuth) {
        const bool fromTrunk = parent.level == 0;
        // Spread along the parent; the trunk keeps its lower part bare.
        const float lo = fromTrunk ? 0.32f : 0.22f;
        const float hi = fromTrunk ? 0.97f : 0.95f;
        const float slot = (static_cast<float>(index) + 0.5f + mRng.uniform(-0.3f, 0.3f)) /
                           static_cast<float>(level.children);
        const float s = lo + (hi - lo) * slot;
        const Ring at = ringAt(rings, level, s);

        // Phyllotaxis: successive children a golden angle apart, plus jitter.
        const double azimuth = firstAzimuth + 0.381966 * index + 0.04 * (mRng.unit() - 0.5f);
        const glm::vec3 radial = rotateIn(at.u, at.v, azimuth);
        // Low limbs spread wide, high ones point up; deeper levels fork at ~40 degrees.
        const double angle = fromTrunk ? 0.17 - 0.10 * s : 0.10 + 0.03 * (mRng.unit() - 0.5f);
        glm::vec3 direction = rotateIn(at.direction, radial, angle);
        if (parent.level < 2)
            direction = glm::normalize(direction + 0.2f * kUp);

        Limb child{};
        child.level = parent.level + 1;
        child.base = at.center;
        child.direction = direction;
        child.hint = at.direction;
        const float jitter = mRng.uniform(0.85f, 1.15f);
        static constexpr std::array<float, 5> kLengthRatio = {0.0f, 0.72f, 0.48f, 0.5f, 0.55f};
        const float taper = fromTrunk ? 1.05f - 0.6f * s : 1.0f - 0.35f * s;
        child.length = parent.length * kLengthRatio[child.level] * taper * jitter;
        child.baseRadius = at.radius * 0.62f;
        child.tipRadius = child.baseRadius * 0.45f;
        return child;
    }

    Status emitTube(
            const std::array<Ring, kMaxSegments + 1>& rings,
            const LimbLevel& level,
            const glm::vec4& color) {
        std::array<SourceVertex, kMaxSides + 1> lower{};
        std::array<SourceVertex, kMaxSides + 1> upper{};
        auto fill = [&](const Ring& ring, std::array<SourceVertex, kMaxSides + 1>& out) {
            for (std::uint32_t j = 0; j <= level.sides; ++j) {
                const glm::vec3 outward =
                        rotateIn(ring.u, ring.v, static_cast<double>(j) / level.sides);
                out[j] = SourceVertex{ring.center + ring.radius * outward, outward, color};
            }
        };
        fill(rings[0], lower);
        for (std::uint32_t k = 1; k <= level.segments; ++k) {
            fill(rings[k], upper);
            for (std::uint32_t j = 0; j < level.sides; ++j) {
                // a, b around the lower ring; d, c above them. Outward counter-clockwise.
                const SourceVertex& a = lower[j];
                const SourceVertex& b = lower[j + 1];
                const SourceVertex& c = upper[j + 1];
                const SourceVertex& d = upper[j];
                FF_RETURN_IF_ERROR(add(a, b, c));
                FF_RETURN_IF_ERROR(add(a, c, d));
            }
            lower = upper;
        }
        return Status::ok();
    }

    /** A leaf folded along its midrib: base, two edge points, tip, raised centre; 4 triangles. */
    Status emitLeaf(
            const std::array<Ring, kMaxSegments + 1>& rings,
            const LimbLevel& level,
            std::uint32_t index) {
        const float slot =
                (static_cast<float>(index) + mRng.unit()) / static_cast<float>(level.leaves);
        const Ring at = ringAt(rings, level, 0.1f + 0.9f * slot);
        const glm::vec3 radial = rotateIn(at.u, at.v, mRng.unit());
        const glm::vec3 along = glm::normalize(
                0.8f * radial + 0.6f * at.direction + 0.3f * kUp + 0.5f * randomUnitVector(mRng));
        const glm::vec3 across = perpendicular(along, randomUnitVector(mRng));
        const glm::vec3 normal = glm::cross(along, across); // unit; the side the fold bulges to

        const float length = kLeafLength * mRng.uniform(0.75f, 1.25f);
        const float width = length * mRng.uniform(0.4f, 0.55f);
        const glm::vec3 base = at.center + at.radius * radial;

        // Linear-RGB greens, a few leaves turning yellow.
        glm::vec4 color(
                mRng.uniform(0.02f, 0.07f),
                mRng.uniform(0.12f, 0.28f),
                mRng.uniform(0.01f, 0.035f),
                1.0f);
        if (mRng.below(16) == 0)
            color.r += 0.12f;

        const SourceVertex b{base, normal, color};
        const SourceVertex t{base + length * along, normal, color};
        const SourceVertex m{base + 0.5f * length * along + 0.12f * length * normal, normal, color};
        const SourceVertex l{base + 0.45f * length * along - 0.5f * width * across, normal, color};
        const SourceVertex r{base + 0.45f * length * along + 0.5f * width * across, normal, color};
        FF_RETURN_IF_ERROR(add(b, l, m));
        FF_RETURN_IF_ERROR(add(l, t, m));
        FF_RETURN_IF_ERROR(add(b, m, r));
        return add(m, t, r);
    }

    TriangleBatcher mOut;
    SplitMix64 mRng;
    float mMaxRadial2 = 0.0f;
};

bool isPowerOf4(std::uint64_t n) noexcept {
    return n != 0 && (n & (n - 1)) == 0 && (n & 0x5555555555555555ull) != 0;
}

/** Even bits of `i` packed together: the x (or, shifted, z) of a Morton index. */
std::uint64_t compactEvenBits(std::uint64_t i) noexcept {
    std::uint64_t out = 0;
    for (unsigned bit = 0; bit < 32; ++bit)
        out |= ((i >> (2 * bit)) & 1ull) << bit;
    return out;
}

Result<GeneratorReport> runForest(const GeneratorSpec& spec, ISceneSink& sink) {
    const ParamReader reader("forest", spec, kParams);
    FF_RETURN_IF_ERROR(reader.checkKnownKeys());
    FF_ASSIGN_OR_RETURN(const std::uint64_t trees, reader.integer("trees", 1, kMaxTrees));
    if (!isPowerOf4(trees))
        return reader.invalid(
                "trees",
                "must be a power of 4 (1, 4, 16, 64, ...) for the recursive 2x2 layout, got " +
                        std::to_string(trees));
    FF_ASSIGN_OR_RETURN(const std::uint64_t seed, reader.integer("seed", 0, ~0ull));

    FF_ASSIGN_OR_RETURN(const PrototypeId prototype, sink.addPrototype("tree"));
    TreeEmitter tree(sink, prototype, seed);
    FF_RETURN_IF_ERROR(tree.grow());
    FF_ASSERT(tree.triangles() == kTreeTriangles);

    // Recursive 2x2 layout (Chamberlain §5.2): instance i sits at the Morton-decoded cell of a
    // sqrt(N) x sqrt(N) grid, so every aligned block of 4^k instances is itself a square. Spacing
    // 1.2 crown diameters keeps trees scaled up to 1.1 from touching.
    std::uint64_t side = 1;
    while (side * side < trees)
        side *= 2;
    const double spacing = 1.2 * 2.0 * static_cast<double>(tree.crownRadius());
    const double middle = 0.5 * static_cast<double>(side - 1);
    SplitMix64 rng(streamSeed(seed, 2));
    for (std::uint64_t i = 0; i < trees; ++i) {
        const auto column = static_cast<double>(compactEvenBits(i));
        const auto row = static_cast<double>(compactEvenBits(i >> 1));
        const glm::vec3 position(
                static_cast<float>((column - middle) * spacing),
                0.0f,
                static_cast<float>((row - middle) * spacing));
        const double yaw = rng.unit();
        const float scale = rng.uniform(0.9f, 1.1f);
        FF_RETURN_IF_ERROR(sink.addInstance(prototype, glm::dmat4(makeTransform(position, yaw, scale))));
    }

    GeneratorReport report;
    report.storedTriangles = tree.triangles();
    report.triangles = report.storedTriangles * trees;
    report.prototypes = 1;
    report.instances = trees;
    return report;
}

} // namespace

GeneratorEntry forestGenerator() {
    return {makeGeneratorInfo(
                    "forest",
                    "one procedural ~52k-triangle tree instanced N = 4^k times in a recursive 2x2 "
                    "grid (Chamberlain et al. '96 tree-quadrupling scenes)",
                    kParams),
            &runForest};
}

} // namespace ff::builder::generators
