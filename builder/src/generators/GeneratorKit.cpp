#include "GeneratorKit.h"

#include <ff/storage/VertexCodec.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <initializer_list>
#include <string>
#include <system_error>

namespace ff::builder::generators {

namespace {

constexpr double kTwoPi = 6.283185307179586476925286766559;

// Taylor coefficients 1/n!, evaluated by the compiler (correctly rounded constants).
constexpr double kInvFact3 = 1.0 / 6.0;
constexpr double kInvFact5 = 1.0 / 120.0;
constexpr double kInvFact7 = 1.0 / 5040.0;
constexpr double kInvFact9 = 1.0 / 362880.0;
constexpr double kInvFact11 = 1.0 / 39916800.0;
constexpr double kInvFact13 = 1.0 / 6227020800.0;
constexpr double kInvFact15 = 1.0 / 1307674368000.0;
constexpr double kInvFact2 = 1.0 / 2.0;
constexpr double kInvFact4 = 1.0 / 24.0;
constexpr double kInvFact6 = 1.0 / 720.0;
constexpr double kInvFact8 = 1.0 / 40320.0;
constexpr double kInvFact10 = 1.0 / 3628800.0;
constexpr double kInvFact12 = 1.0 / 479001600.0;
constexpr double kInvFact14 = 1.0 / 87178291200.0;
constexpr double kInvFact16 = 1.0 / 20922789888000.0;

/** Joins message parts. Used instead of operator+ chains, on which GCC 12 -O3 emits a false
 *  -Wrestrict (GCC bug 105329) that -Werror turns into a build failure. */
std::string concat(std::initializer_list<std::string_view> parts) {
    std::string out;
    for (const std::string_view part : parts)
        out.append(part);
    return out;
}

/** The shortest text that reads back as `value` ("0.0001", not "0.000100"). */
std::string shortest(double value) {
    std::array<char, 32> buffer{};
    const auto result = std::to_chars(buffer.data(), buffer.data() + buffer.size(), value);
    return std::string(buffer.data(), result.ptr);
}

} // namespace

SinCos sinCosTurns(double turns) noexcept {
    const double quarter = std::floor(turns * 4.0 + 0.5);
    const double x = (turns - quarter * 0.25) * kTwoPi; // in [-pi/4, pi/4]
    const double x2 = x * x;
    const double s =
            x *
            (1.0 -
             x2 * (kInvFact3 -
                   x2 * (kInvFact5 -
                         x2 * (kInvFact7 -
                               x2 * (kInvFact9 -
                                     x2 * (kInvFact11 - x2 * (kInvFact13 - x2 * kInvFact15)))))));
    const double c =
            1.0 - x2 * (kInvFact2 -
                        x2 * (kInvFact4 -
                              x2 * (kInvFact6 -
                                    x2 * (kInvFact8 -
                                          x2 * (kInvFact10 -
                                                x2 * (kInvFact12 -
                                                      x2 * (kInvFact14 - x2 * kInvFact16)))))));
    // Two's complement (guaranteed since C++20) makes `& 3` a true modulo for negative quarters.
    switch (static_cast<std::int64_t>(quarter) & 3) {
    case 0:
        return {s, c};
    case 1:
        return {c, -s};
    case 2:
        return {-s, -c};
    default:
        return {-c, s};
    }
}

GeneratorInfo makeGeneratorInfo(
        std::string_view name, std::string_view summary, std::span<const ParamDef> params) {
    GeneratorInfo info;
    info.name = std::string(name);
    info.summary = std::string(summary);
    for (const ParamDef& def : params)
        info.params.emplace_back(
                std::string(def.key), concat({def.defaultValue, ": ", def.meaning}));
    return info;
}

Status ParamReader::checkKnownKeys() const {
    for (const auto& param : mSpec.params) {
        // Not a structured binding: clang < 16 cannot capture those in a lambda.
        const std::string& key = param.first;
        const bool known = std::any_of(
                mDefs.begin(), mDefs.end(), [&](const ParamDef& def) { return def.key == key; });
        if (!known) {
            std::string keys;
            for (const ParamDef& def : mDefs)
                keys.append(keys.empty() ? "" : ", ").append(def.key);
            return Status(
                    ErrorCode::InvalidArgument,
                    concat({mGenerator, ": unknown parameter '", key, "' (known: ", keys, ")"}));
        }
    }
    return Status::ok();
}

std::string_view ParamReader::text(std::string_view key) const {
    if (const auto it = mSpec.params.find(key); it != mSpec.params.end())
        return it->second;
    for (const ParamDef& def : mDefs)
        if (def.key == key)
            return def.defaultValue;
    FF_ASSERT(false && "generator reads a parameter missing from its own ParamDef table");
    return {};
}

Result<std::uint64_t>
ParamReader::integer(std::string_view key, std::uint64_t min, std::uint64_t max) const {
    const std::string_view value = text(key);
    std::uint64_t parsed = 0;
    const auto [end, error] = std::from_chars(value.data(), value.data() + value.size(), parsed);
    if (error == std::errc::result_out_of_range)
        return invalid(key, concat({"'", value, "' is too large"}));
    if (value.empty() || error != std::errc() || end != value.data() + value.size())
        return invalid(key, concat({"expected a non-negative integer, got '", value, "'"}));
    if (parsed < min || parsed > max)
        return invalid(
                key,
                concat({"must be in [",
                        std::to_string(min),
                        ", ",
                        std::to_string(max),
                        "], got ",
                        value}));
    return parsed;
}

Result<double> ParamReader::real(std::string_view key, double min, double max) const {
    const std::string_view value = text(key);
    double parsed = 0.0;
    const auto [end, error] = std::from_chars(value.data(), value.data() + value.size(), parsed);
    if (value.empty() || error != std::errc() || end != value.data() + value.size() ||
        !std::isfinite(parsed))
        return invalid(key, concat({"expected a finite number, got '", value, "'"}));
    if (parsed < min || parsed > max)
        return invalid(
                key,
                concat({"must be in [", shortest(min), ", ", shortest(max), "], got ", value}));
    return parsed;
}

Status ParamReader::invalid(std::string_view key, std::string_view why) const {
    return Status(
            ErrorCode::InvalidArgument, concat({mGenerator, ": parameter '", key, "': ", why}));
}

TriangleBatcher::TriangleBatcher(ISceneSink& sink, PrototypeId prototype)
    : mSink(sink)
    , mPrototype(prototype) {
    mBatch.reserve(kBatchTriangles);
}

Status TriangleBatcher::flush() {
    if (mBatch.empty())
        return Status::ok();
    FF_RETURN_IF_ERROR(mSink.addTriangles(mPrototype, mBatch));
    mSent += mBatch.size();
    mBatch.clear();
    return Status::ok();
}

Result<GeneratorReport> flushSingleMesh(TriangleBatcher& out) {
    FF_RETURN_IF_ERROR(out.flush());
    GeneratorReport report;
    report.storedTriangles = out.added();
    report.triangles = report.storedTriangles;
    report.prototypes = 1;
    report.instances = 1;
    return report;
}

glm::mat4 makeTransform(const glm::vec3& translation, double yawTurns, float scale) noexcept {
    const SinCos r = sinCosTurns(yawTurns);
    const float c = static_cast<float>(r.cos) * scale;
    const float s = static_cast<float>(r.sin) * scale;
    glm::mat4 m(1.0f);
    m[0] = glm::vec4(c, 0.0f, -s, 0.0f); // rotation about +Y (right-handed, Y up)
    m[1] = glm::vec4(0.0f, scale, 0.0f, 0.0f);
    m[2] = glm::vec4(s, 0.0f, c, 0.0f);
    m[3] = glm::vec4(translation, 1.0f);
    return m;
}

Box axisBox(const glm::vec3& lo, const glm::vec3& hi) noexcept {
    const glm::vec3 half = 0.5f * (hi - lo);
    return {0.5f * (lo + hi), {glm::vec3(1, 0, 0), glm::vec3(0, 1, 0), glm::vec3(0, 0, 1)}, {half.x, half.y, half.z}};
}

Status emitBox(const Box& box, const std::array<std::uint32_t, 3>& segments, const glm::vec4& color, TriangleBatcher& out) {
    for (int a = 0; a < 3; ++a) {
        const auto ia = static_cast<std::size_t>(a);
        const auto iu = static_cast<std::size_t>((a + 1) % 3);
        const auto iv = static_cast<std::size_t>((a + 2) % 3);
        for (const float side : {1.0f, -1.0f}) {
            const glm::vec3 normal = side * box.axis[ia];
            // u x v must equal the outward normal for counter-clockwise corners.
            const glm::vec3 u = (side > 0.0f ? box.axis[iu] : box.axis[iv]) *
                                (side > 0.0f ? box.half[iu] : box.half[iv]);
            const glm::vec3 v = (side > 0.0f ? box.axis[iv] : box.axis[iu]) *
                                (side > 0.0f ? box.half[iv] : box.half[iu]);
            const std::uint32_t nu = side > 0.0f ? segments[iu] : segments[iv];
            const std::uint32_t nv = side > 0.0f ? segments[iv] : segments[iu];
            const glm::vec3 faceCenter = box.center + normal * box.half[ia];
            // Grid coordinates -1..1; with one segment these are exactly -u-v, +u-v, ...
            auto corner = [&](std::uint32_t i, std::uint32_t j) {
                const float fu = 2.0f * static_cast<float>(i) / static_cast<float>(nu) - 1.0f;
                const float fv = 2.0f * static_cast<float>(j) / static_cast<float>(nv) - 1.0f;
                return SourceVertex{faceCenter + fu * u + fv * v, normal, color};
            };
            for (std::uint32_t j = 0; j < nv; ++j) {
                for (std::uint32_t i = 0; i < nu; ++i) {
                    const std::array<SourceVertex, 4> quad = {
                            corner(i, j), corner(i + 1, j), corner(i + 1, j + 1), corner(i, j + 1)};
                    FF_RETURN_IF_ERROR(out.add(quad[0], quad[1], quad[2]));
                    FF_RETURN_IF_ERROR(out.add(quad[0], quad[2], quad[3]));
                }
            }
        }
    }
    return Status::ok();
}

} // namespace ff::builder::generators
