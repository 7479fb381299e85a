// Camera path interpolation and its JSON format (docs/camera-paths.md).
//
// References:
//  - P. J. Barry, R. N. Goldman, "A recursive evaluation algorithm for a class of Catmull-Rom
//    splines", SIGGRAPH 1988 (the pyramidal evaluation used by catmullRom()).
//  - C. Yuksel, S. Schaefer, J. Keyser, "Parameterization and applications of Catmull-Rom
//    curves", CAD 43(7), 2011 (centripetal knots: no cusps or self-intersections in a segment).
//  - F. N. Fritsch, R. E. Carlson, "Monotone piecewise cubic interpolation", SINUM 17(2), 1980;
//    F. N. Fritsch, J. Butland, "A method for constructing local monotone piecewise cubic
//    interpolants", SISSC 5(2), 1984 (the slopes of monotoneSlopes(), as in SciPy's PCHIP).
//  - K. Shoemake, "Animating rotation with quaternion curves", SIGGRAPH 1985 (slerp, squad).
//
// Why time is mapped onto the centripetal knots by a monotone cubic rather than used as the
// knots: Catmull-Rom with time knots overshoots and loops where keyframes are unevenly spaced in
// space; centripetal knots do not, but are C1 only in their own parameter. Composing the curve
// with a C1, strictly increasing knot(time) keeps both the shape and C1 smoothness in time.

#include <ff/runtime/CameraPath.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <sstream>

namespace ff::runtime {

namespace {

constexpr const char* kFormatName = "farfield-camera-path";
constexpr int kFormatVersion = 1;
constexpr double kUnitTolerance = 1e-3;        // |quaternion| may differ from 1 by this much
constexpr std::int64_t kMaxFrames = 1LL << 40; // a frame count beyond this is a typo

using nlohmann::json;

std::string formatNumber(double value) {
    std::ostringstream out;
    out << value;
    return out.str();
}

// ---- quaternions (unit, double precision) ---------------------------------------------------

/** Slerp without choosing the shorter arc (squad needs the arc it is given). */
glm::dquat slerpArc(const glm::dquat& a, const glm::dquat& b, double u) {
    if (a == b) // holds stay bit-exact
        return a;
    const double cosine = std::clamp(glm::dot(a, b), -1.0, 1.0);
    if (cosine > 0.9999) // nearly equal: sin(theta) is too small to divide by
        return glm::normalize(a * (1.0 - u) + b * u);
    const double theta = std::acos(cosine);
    const double sine = std::sin(theta);
    return glm::normalize(
            a * (std::sin((1.0 - u) * theta) / sine) + b * (std::sin(u * theta) / sine));
}

/** log of a unit quaternion: (0, axis * angle / 2) as a vector. */
glm::dvec3 logUnit(const glm::dquat& q) {
    const glm::dvec3 v(q.x, q.y, q.z);
    const double sine = glm::length(v);
    if (sine < 1e-12)
        return glm::dvec3(0.0);
    return v * (std::atan2(sine, std::clamp(q.w, -1.0, 1.0)) / sine);
}

/** exp of the pure quaternion (0, v). */
glm::dquat expPure(const glm::dvec3& v) {
    const double theta = glm::length(v);
    if (theta < 1e-12)
        return glm::normalize(glm::dquat(1.0, v.x, v.y, v.z));
    const glm::dvec3 axis = v * (std::sin(theta) / theta);
    return glm::dquat(std::cos(theta), axis.x, axis.y, axis.z);
}

// ---- scalar and curve interpolation ------------------------------------------------------

/** Cubic Hermite on one interval of length h at u in [0, 1]. */
double hermite(double p0, double p1, double m0, double m1, double h, double u) {
    const double u2 = u * u;
    const double u3 = u2 * u;
    return (2.0 * u3 - 3.0 * u2 + 1.0) * p0 + (u3 - 2.0 * u2 + u) * h * m0 +
           (-2.0 * u3 + 3.0 * u2) * p1 + (u3 - u2) * h * m1;
}

int sign(double v) {
    return (v > 0.0) - (v < 0.0);
}

/** Slopes of the shape-preserving piecewise cubic through (x[i], y[i]) (Fritsch-Butland). */
std::vector<double> monotoneSlopes(const std::vector<double>& x, const std::vector<double>& y) {
    const std::size_t n = x.size();
    std::vector<double> slopes(n, 0.0);
    if (n < 2)
        return slopes;
    std::vector<double> h(n - 1);
    std::vector<double> secant(n - 1);
    for (std::size_t i = 0; i + 1 < n; ++i) {
        h[i] = x[i + 1] - x[i];
        secant[i] = (y[i + 1] - y[i]) / h[i];
    }
    if (n == 2) {
        slopes[0] = slopes[1] = secant[0];
        return slopes;
    }
    for (std::size_t i = 1; i + 1 < n; ++i) {
        const double a = secant[i - 1];
        const double b = secant[i];
        if (sign(a) == 0 || sign(a) != sign(b))
            continue; // an extremum or a flat piece: zero slope keeps the shape
        const double w1 = 2.0 * h[i] + h[i - 1];
        const double w2 = h[i] + 2.0 * h[i - 1];
        slopes[i] = (w1 + w2) / (w1 / a + w2 / b);
    }
    // Ends: one-sided three-point estimate, limited so the end intervals stay shape-preserving.
    const auto endSlope = [](double h0, double h1, double s0, double s1) {
        double d = ((2.0 * h0 + h1) * s0 - h0 * s1) / (h0 + h1);
        if (sign(d) != sign(s0))
            d = 0.0;
        else if (sign(s0) != sign(s1) && std::fabs(d) > 3.0 * std::fabs(s0))
            d = 3.0 * s0;
        return d;
    };
    slopes[0] = endSlope(h[0], h[1], secant[0], secant[1]);
    slopes[n - 1] = endSlope(h[n - 2], h[n - 3], secant[n - 2], secant[n - 3]);
    return slopes;
}

/**
 * The non-uniform Catmull-Rom curve through p1 (at knot t1) and p2 (at t2) with neighbours p0, p3,
 * evaluated at knot value t in [t1, t2] (Barry & Goldman's pyramid). Knots strictly increasing.
 */
glm::dvec3 catmullRom(
        const glm::dvec3& p0,
        const glm::dvec3& p1,
        const glm::dvec3& p2,
        const glm::dvec3& p3,
        double t0,
        double t1,
        double t2,
        double t3,
        double t) {
    const glm::dvec3 a1 = ((t1 - t) * p0 + (t - t0) * p1) / (t1 - t0);
    const glm::dvec3 a2 = ((t2 - t) * p1 + (t - t1) * p2) / (t2 - t1);
    const glm::dvec3 a3 = ((t3 - t) * p2 + (t - t2) * p3) / (t3 - t2);
    const glm::dvec3 b1 = ((t2 - t) * a1 + (t - t0) * a2) / (t2 - t0);
    const glm::dvec3 b2 = ((t3 - t) * a2 + (t - t1) * a3) / (t3 - t1);
    return ((t2 - t) * b1 + (t - t1) * b2) / (t2 - t1);
}

// ---- validation ----------------------------------------------------------------------------

std::string keyframeKey(std::size_t index, const char* key) {
    return "keyframes[" + std::to_string(index) + "]." + key;
}

bool finite3(const glm::dvec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

Status validateKeyframe(const CameraKeyframe& k, std::size_t index) {
    const auto invalid = [index](const char* key, const std::string& what) {
        return Status(ErrorCode::InvalidArgument, keyframeKey(index, key) + ": " + what);
    };
    if (!std::isfinite(k.time))
        return invalid("time", "not a finite number");
    if (!finite3(k.position))
        return invalid("position", "not a finite point");
    constexpr double kFloatMax = std::numeric_limits<float>::max();
    if (std::fabs(k.position.x) > kFloatMax || std::fabs(k.position.y) > kFloatMax ||
        std::fabs(k.position.z) > kFloatMax)
        return invalid("position", "beyond the range of float");
    const glm::dquat& q = k.orientation;
    if (!std::isfinite(q.w) || !std::isfinite(q.x) || !std::isfinite(q.y) || !std::isfinite(q.z))
        return invalid("orientation", "not finite");
    const double length = glm::length(q);
    if (std::fabs(length - 1.0) > kUnitTolerance)
        return invalid(
                "orientation", "not a unit quaternion (length " + formatNumber(length) + ")");
    if (!(k.fovDegrees > 0.0 && k.fovDegrees < 180.0))
        return invalid("fov", "must be in (0, 180) degrees, is " + formatNumber(k.fovDegrees));
    return Status::ok();
}

// ---- JSON reading ------------------------------------------------------------------------

Status invalidInput(const std::string& where, const std::string& what) {
    return Status(ErrorCode::InvalidInput, where + ": " + what);
}

Status readNumber(const json& value, const std::string& where, double& out) {
    if (!value.is_number())
        return invalidInput(where, std::string("expected a number, got ") + value.type_name());
    out = value.get<double>();
    if (!std::isfinite(out))
        return invalidInput(where, "not a finite number");
    return Status::ok();
}

Status readNumbers(const json& value, const std::string& where, std::size_t count, double* out) {
    if (!value.is_array() || value.size() != count)
        return invalidInput(where, "expected an array of " + std::to_string(count) + " numbers");
    for (std::size_t i = 0; i < count; ++i)
        FF_RETURN_IF_ERROR(readNumber(value[i], where + "[" + std::to_string(i) + "]", out[i]));
    return Status::ok();
}

Status readVec3(const json& value, const std::string& where, glm::dvec3& out) {
    double v[3];
    FF_RETURN_IF_ERROR(readNumbers(value, where, 3, v));
    out = {v[0], v[1], v[2]};
    return Status::ok();
}

Status
checkKeys(const json& object, const std::string& where, const std::set<std::string>& allowed) {
    for (const auto& item : object.items())
        if (!allowed.contains(item.key()))
            return invalidInput(
                    where.empty() ? item.key() : where + "." + item.key(), "unknown key");
    return Status::ok();
}

Result<CameraKeyframe> readKeyframe(const json& value, std::size_t index, double defaultFov) {
    const std::string where = "keyframes[" + std::to_string(index) + "]";
    if (!value.is_object())
        return invalidInput(where, std::string("expected an object, got ") + value.type_name());
    FF_RETURN_IF_ERROR(checkKeys(
            value,
            where,
            {"time", "position", "target", "orientation", "forward", "up", "fov", "name"}));
    for (const char* key : {"time", "position"})
        if (!value.contains(key))
            return invalidInput(where, std::string("missing key \"") + key + "\"");

    CameraKeyframe k;
    FF_RETURN_IF_ERROR(readNumber(value["time"], where + ".time", k.time));
    FF_RETURN_IF_ERROR(readVec3(value["position"], where + ".position", k.position));

    const int forms = int(value.contains("target")) + int(value.contains("orientation")) +
                      int(value.contains("forward"));
    if (forms != 1)
        return invalidInput(
                where,
                forms == 0
                        ? "missing key \"target\", \"orientation\" or \"forward\" (one is needed)"
                        : "give only one of \"target\", \"orientation\" and \"forward\"");
    if (value.contains("orientation")) {
        if (value.contains("up"))
            return invalidInput(where + ".up", "only goes with \"target\" or \"forward\"");
        double q[4];
        FF_RETURN_IF_ERROR(readNumbers(value["orientation"], where + ".orientation", 4, q));
        k.orientation = glm::dquat(q[3], q[0], q[1], q[2]); // JSON order x, y, z, w as in glTF
        const double length = glm::length(k.orientation);
        if (std::fabs(length - 1.0) > kUnitTolerance)
            return invalidInput(
                    where + ".orientation",
                    "not a unit quaternion (length " + formatNumber(length) + ")");
    } else {
        glm::dvec3 up(0.0, 1.0, 0.0);
        if (value.contains("up")) {
            FF_RETURN_IF_ERROR(readVec3(value["up"], where + ".up", up));
            if (!(glm::dot(up, up) > 0.0))
                return invalidInput(where + ".up", "zero vector");
        }
        glm::dvec3 forward;
        if (value.contains("target")) {
            glm::dvec3 target;
            FF_RETURN_IF_ERROR(readVec3(value["target"], where + ".target", target));
            forward = target - k.position;
            if (!(glm::dot(forward, forward) > 0.0))
                return invalidInput(where + ".target", "equals the position");
        } else {
            FF_RETURN_IF_ERROR(readVec3(value["forward"], where + ".forward", forward));
            if (!(glm::dot(forward, forward) > 0.0))
                return invalidInput(where + ".forward", "zero vector");
        }
        if (!finite3(forward))
            return invalidInput(where, "view direction overflows");
        k.orientation = lookOrientation(forward, up);
    }

    k.fovDegrees = defaultFov;
    if (value.contains("fov")) {
        FF_RETURN_IF_ERROR(readNumber(value["fov"], where + ".fov", k.fovDegrees));
        if (!(k.fovDegrees > 0.0 && k.fovDegrees < 180.0))
            return invalidInput(
                    where + ".fov",
                    "must be in (0, 180) degrees, is " + formatNumber(k.fovDegrees));
    }
    if (value.contains("name")) {
        if (!value["name"].is_string())
            return invalidInput(where + ".name", "expected a string");
        k.name = value["name"].get<std::string>();
    }
    return k;
}

Result<CameraPath> parsePath(const json& root) {
    if (!root.is_object())
        return Status(
                ErrorCode::InvalidInput,
                std::string("expected a JSON object, got ") + root.type_name());
    FF_RETURN_IF_ERROR(checkKeys(
            root, "", {"format", "version", "interpolation", "fps", "frames", "fov", "keyframes"}));
    if (root.contains("format") && root["format"] != kFormatName)
        return invalidInput("format", std::string("expected \"") + kFormatName + "\"");
    if (root.contains("version")) {
        if (!root["version"].is_number_integer())
            return invalidInput("version", "expected an integer");
        if (root["version"].get<std::int64_t>() != kFormatVersion)
            return Status(
                    ErrorCode::Unsupported,
                    "version " + root["version"].dump() + " is not supported (only " +
                            std::to_string(kFormatVersion) + ")");
    }

    PathInterpolation interpolation = PathInterpolation::Linear;
    if (root.contains("interpolation")) {
        const json& value = root["interpolation"];
        if (value == "linear")
            interpolation = PathInterpolation::Linear;
        else if (value == "spline")
            interpolation = PathInterpolation::Spline;
        else
            return invalidInput(
                    "interpolation", "unknown value " + value.dump() + " (linear or spline)");
    }

    FrameSampling sampling;
    if (root.contains("fps") && root.contains("frames"))
        return invalidInput("frames", "give \"fps\" or \"frames\", not both");
    if (root.contains("fps")) {
        FF_RETURN_IF_ERROR(readNumber(root["fps"], "fps", sampling.fps));
        if (!(sampling.fps > 0.0))
            return invalidInput("fps", "must be positive");
    }
    if (root.contains("frames")) {
        const json& value = root["frames"];
        if (!value.is_number_integer() || value.get<std::int64_t>() < 1 ||
            value.get<std::int64_t>() > kMaxFrames)
            return invalidInput("frames", "expected an integer from 1 to 2^40");
        sampling = FrameSampling::frames(value.get<std::int64_t>());
    }

    double defaultFov = 45.0;
    if (root.contains("fov")) {
        FF_RETURN_IF_ERROR(readNumber(root["fov"], "fov", defaultFov));
        if (!(defaultFov > 0.0 && defaultFov < 180.0))
            return invalidInput(
                    "fov", "must be in (0, 180) degrees, is " + formatNumber(defaultFov));
    }

    if (!root.contains("keyframes"))
        return Status(ErrorCode::InvalidInput, "missing key \"keyframes\"");
    const json& frames = root["keyframes"];
    if (!frames.is_array())
        return invalidInput(
                "keyframes", std::string("expected an array, got ") + frames.type_name());
    if (frames.empty())
        return invalidInput("keyframes", "needs at least 1 keyframe");
    std::vector<CameraKeyframe> keyframes;
    keyframes.reserve(frames.size());
    for (std::size_t i = 0; i < frames.size(); ++i) {
        FF_ASSIGN_OR_RETURN(CameraKeyframe k, readKeyframe(frames[i], i, defaultFov));
        keyframes.push_back(std::move(k));
    }
    Result<CameraPath> path = CameraPath::create(std::move(keyframes), interpolation, sampling);
    if (!path)
        return Status(ErrorCode::InvalidInput, path.status().message());
    return path;
}

/** The values for JSON, with -0 written as 0 (a quaternion component is often an exact -0). */
std::vector<double> numbers(std::initializer_list<double> values) {
    std::vector<double> out;
    for (const double v : values)
        out.push_back(v == 0.0 ? 0.0 : v);
    return out;
}

} // namespace

const char* pathInterpolationName(PathInterpolation interpolation) noexcept {
    return interpolation == PathInterpolation::Spline ? "spline" : "linear";
}

glm::dquat lookOrientation(const glm::dvec3& forward, const glm::dvec3& upHint) {
    FF_ASSERT(glm::dot(forward, forward) > 0.0);
    const glm::dvec3 f = glm::normalize(forward);
    glm::dvec3 right = glm::cross(f, upHint);
    if (!(glm::dot(right, right) >
          1e-20 * glm::dot(upHint, upHint))) // along the hint: any perpendicular
        right = glm::cross(f, std::fabs(f.y) < 0.9 ? glm::dvec3(0, 1, 0) : glm::dvec3(1, 0, 0));
    right = glm::normalize(right);
    const glm::dvec3 up = glm::cross(right, f);
    // Columns: where the camera's +X, +Y, +Z axes go; the camera looks down its -Z.
    return glm::normalize(glm::quat_cast(glm::dmat3(right, up, -f)));
}

Result<CameraPath> CameraPath::create(
        std::vector<CameraKeyframe> keyframes,
        PathInterpolation interpolation,
        FrameSampling sampling) {
    if (keyframes.empty())
        return Status(ErrorCode::InvalidArgument, "keyframes: needs at least 1 keyframe");
    for (std::size_t i = 0; i < keyframes.size(); ++i) {
        FF_RETURN_IF_ERROR(validateKeyframe(keyframes[i], i));
        if (i > 0 && !(keyframes[i].time > keyframes[i - 1].time))
            return Status(
                    ErrorCode::InvalidArgument,
                    keyframeKey(i, "time") + ": " + formatNumber(keyframes[i].time) +
                            " is not after keyframes[" + std::to_string(i - 1) + "].time (" +
                            formatNumber(keyframes[i - 1].time) + "); times must increase");
        keyframes[i].orientation = glm::normalize(keyframes[i].orientation);
    }
    if (sampling.count < 0 || sampling.count > kMaxFrames)
        return Status(ErrorCode::InvalidArgument, "frames: must be from 1 to 2^40");
    if (sampling.count == 0) {
        const double frames = (keyframes.back().time - keyframes.front().time) * sampling.fps;
        if (!(sampling.fps > 0.0) || !std::isfinite(sampling.fps))
            return Status(ErrorCode::InvalidArgument, "fps: must be positive");
        if (!(frames < static_cast<double>(kMaxFrames)))
            return Status(ErrorCode::InvalidArgument, "fps: more than 2^40 frames over the path");
    }

    CameraPath path;
    path.mKeyframes = std::move(keyframes);
    path.mInterpolation = interpolation;
    path.mSampling = sampling;
    const std::vector<CameraKeyframe>& k = path.mKeyframes;
    const std::size_t n = k.size();

    // Quaternions q and -q are one rotation; flip each into its predecessor's hemisphere so that
    // interpolation takes the shorter arc.
    path.mAligned.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        glm::dquat q = k[i].orientation;
        if (i > 0 && glm::dot(path.mAligned[i - 1], q) < 0.0)
            q = -q;
        path.mAligned[i] = q;
    }
    if (interpolation == PathInterpolation::Linear || n < 2)
        return path;

    // Centripetal knots, with a floor on the spacing so that repeated positions (holds) keep
    // strictly increasing knots; the curve barely moves over such a tiny interval.
    std::vector<double> spacing(n - 1);
    double largest = 0.0;
    for (std::size_t i = 0; i + 1 < n; ++i) {
        spacing[i] = std::sqrt(glm::length(k[i + 1].position - k[i].position));
        largest = std::max(largest, spacing[i]);
    }
    const double minSpacing = largest > 0.0 ? largest * 1e-9 : 1.0;
    path.mKnots.resize(n);
    path.mKnots[0] = 0.0;
    for (std::size_t i = 0; i + 1 < n; ++i)
        path.mKnots[i + 1] = path.mKnots[i] + std::max(spacing[i], minSpacing);

    std::vector<double> times(n);
    std::vector<double> fovs(n);
    for (std::size_t i = 0; i < n; ++i) {
        times[i] = k[i].time;
        fovs[i] = k[i].fovDegrees;
    }
    path.mKnotSlopes = monotoneSlopes(times, path.mKnots);
    path.mFovSlopes = monotoneSlopes(times, fovs);

    // Squad's inner quaternions a_i = q_i exp(-(log(q_i^-1 q_{i+1}) + log(q_i^-1 q_{i-1})) / 4).
    path.mSquadInner = path.mAligned;
    for (std::size_t i = 1; i + 1 < n; ++i) {
        const glm::dquat& q = path.mAligned[i];
        const glm::dquat inverse = glm::conjugate(q);
        const glm::dvec3 sum =
                logUnit(inverse * path.mAligned[i + 1]) + logUnit(inverse * path.mAligned[i - 1]);
        path.mSquadInner[i] = glm::normalize(q * expPure(-0.25 * sum));
    }
    return path;
}

CameraPose CameraPath::poseInSegment(std::size_t i, double time) const {
    const CameraKeyframe& a = mKeyframes[i];
    const CameraKeyframe& b = mKeyframes[i + 1];
    const double h = b.time - a.time;
    const double u = std::clamp((time - a.time) / h, 0.0, 1.0);
    CameraPose pose;
    if (mInterpolation == PathInterpolation::Linear) {
        // a + (b - a) u, not a (1 - u) + b u: equal keyframes (holds) give bit-identical frames.
        pose.position = a.position + (b.position - a.position) * u;
        pose.orientation = slerpArc(mAligned[i], mAligned[i + 1], u);
        pose.fovDegrees = a.fovDegrees + (b.fovDegrees - a.fovDegrees) * u;
        return pose;
    }

    // Position: knot(time) by the monotone cubic, then the centripetal curve at that knot. The
    // ends get phantom neighbours mirrored through the end keyframes (same knot spacing).
    const std::size_t n = mKeyframes.size();
    const std::vector<double>& s = mKnots;
    const double knot = std::clamp(
            hermite(s[i], s[i + 1], mKnotSlopes[i], mKnotSlopes[i + 1], h, u), s[i], s[i + 1]);
    const glm::dvec3 p0 = i > 0 ? mKeyframes[i - 1].position : 2.0 * a.position - b.position;
    const double s0 = i > 0 ? s[i - 1] : 2.0 * s[0] - s[1];
    const glm::dvec3 p3 = i + 2 < n ? mKeyframes[i + 2].position : 2.0 * b.position - a.position;
    const double s3 = i + 2 < n ? s[i + 2] : 2.0 * s[i + 1] - s[i];
    pose.position = catmullRom(p0, a.position, b.position, p3, s0, s[i], s[i + 1], s3, knot);

    pose.fovDegrees = hermite(a.fovDegrees, b.fovDegrees, mFovSlopes[i], mFovSlopes[i + 1], h, u);
    pose.orientation = slerpArc(
            slerpArc(mAligned[i], mAligned[i + 1], u),
            slerpArc(mSquadInner[i], mSquadInner[i + 1], u),
            2.0 * u * (1.0 - u));
    return pose;
}

CameraPose CameraPath::pose(double time) const {
    const std::size_t n = mKeyframes.size();
    if (n == 1 || time >= endTime()) {
        const CameraKeyframe& last = mKeyframes.back();
        return {last.position, mAligned.back(), last.fovDegrees};
    }
    if (!(time > startTime())) // also NaN
        time = startTime();
    const auto after = std::upper_bound(
            mKeyframes.begin(), mKeyframes.end(), time, [](double t, const CameraKeyframe& k) {
                return t < k.time;
            });
    const auto segment = static_cast<std::size_t>(after - mKeyframes.begin()) - 1;
    return poseInSegment(segment, time);
}

Camera CameraPath::sample(double time, const glm::dvec3& frameOrigin) const {
    const CameraPose p = pose(time);
    Camera camera;
    camera.eye = glm::vec3(p.position - frameOrigin);
    camera.forward = glm::normalize(glm::vec3(p.forward()));
    camera.up = glm::normalize(glm::vec3(p.up()));
    camera.fovY = static_cast<float>(glm::radians(p.fovDegrees));
    return camera;
}

CameraPath CameraPath::translated(const glm::dvec3& offset) const {
    CameraPath moved = *this;
    for (CameraKeyframe& k : moved.mKeyframes)
        k.position += offset;
    return moved;
}

std::int64_t CameraPath::frameCount() const noexcept {
    if (mSampling.count > 0)
        return mSampling.count;
    const double frames = (endTime() - startTime()) * mSampling.fps;
    // The tolerance keeps a path of (N-1)/fps seconds at N frames despite rounding.
    return static_cast<std::int64_t>(std::floor(frames + 1e-9 * std::max(1.0, frames))) + 1;
}

double CameraPath::frameTime(std::int64_t index) const {
    FF_ASSERT(index >= 0 && index < frameCount());
    if (mSampling.count > 0) {
        if (index == mSampling.count - 1)
            return endTime();
        return startTime() + (endTime() - startTime()) * static_cast<double>(index) /
                                     static_cast<double>(mSampling.count - 1);
    }
    return std::min(startTime() + static_cast<double>(index) / mSampling.fps, endTime());
}

Result<CameraPath> CameraPath::fromJson(std::string_view text) {
    json root;
    try {
        root = json::parse(text.begin(), text.end());
    } catch (const json::exception& e) { // syntax errors, and numbers beyond double ("1e999")
        return Status(ErrorCode::InvalidInput, std::string("not valid JSON: ") + e.what());
    }
    try {
        return parsePath(root);
    } catch (const json::exception& e) { // not expected: every access above checks its type
        return Status(ErrorCode::InvalidInput, e.what());
    }
}

std::string CameraPath::toJson() const {
    // One keyframe per line: paths with a keyframe per frame stay readable and diffable.
    std::string out = "{\n";
    out += "  \"format\": \"" + std::string(kFormatName) + "\",\n";
    out += "  \"version\": " + std::to_string(kFormatVersion) + ",\n";
    out += "  \"interpolation\": \"" + std::string(pathInterpolationName(mInterpolation)) + "\",\n";
    if (mSampling.count > 0)
        out += "  \"frames\": " + std::to_string(mSampling.count) + ",\n";
    else
        out += "  \"fps\": " + json(mSampling.fps).dump() + ",\n";
    out += "  \"keyframes\": [\n";
    for (std::size_t i = 0; i < mKeyframes.size(); ++i) {
        const CameraKeyframe& k = mKeyframes[i];
        nlohmann::ordered_json line = nlohmann::ordered_json::object();
        line["time"] = k.time;
        line["position"] = numbers({k.position.x, k.position.y, k.position.z});
        line["orientation"] =
                numbers({k.orientation.x, k.orientation.y, k.orientation.z, k.orientation.w});
        line["fov"] = k.fovDegrees;
        if (!k.name.empty())
            line["name"] = k.name;
        out += "    " + line.dump() + (i + 1 < mKeyframes.size() ? ",\n" : "\n");
    }
    out += "  ]\n}\n";
    return out;
}

} // namespace ff::runtime
