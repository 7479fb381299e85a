#include <ff/runtime/CameraPathGenerators.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <locale>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

namespace ff::runtime {

namespace {

constexpr glm::dvec3 kUp(0.0, 1.0, 0.0);

/** splitmix64 (Steele, Lea, Flood 2014): a fixed generator, so paths are the same everywhere,
 *  unlike std:: distributions whose output is implementation-defined. */
class SplitMix64 {
public:
    explicit SplitMix64(std::uint64_t seed)
        : mState(seed) {}
    std::uint64_t next() {
        std::uint64_t z = (mState += 0x9e3779b97f4a7c15ULL);
        z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
        z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
        return z ^ (z >> 31);
    }
    /** Uniform in [0, 1). */
    double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }

private:
    std::uint64_t mState;
};

/** The bounds in double precision, every side at least 1e-3 of the largest (a flat scene still
 *  gets a box to move in). */
struct Box {
    glm::dvec3 min;
    glm::dvec3 size;
    glm::dvec3 at(const glm::dvec3& fraction) const { return min + fraction * size; }
    glm::dvec3 center() const { return min + 0.5 * size; }
    double diagonal() const { return glm::length(size); }
};

Result<Box> fitBox(const Bounds& bounds, const PathGeneratorOptions& options) {
    if (options.frames < 1)
        return Status(ErrorCode::InvalidArgument, "frames must be at least 1");
    if (!(options.fps > 0.0) || !std::isfinite(options.fps))
        return Status(ErrorCode::InvalidArgument, "fps must be positive");
    if (!(options.fovDegrees > 0.0 && options.fovDegrees < 180.0))
        return Status(ErrorCode::InvalidArgument, "fov must be in (0, 180) degrees");
    const glm::dvec3 lo(bounds.min);
    const glm::dvec3 hi(bounds.max);
    for (int axis = 0; axis < 3; ++axis)
        if (!std::isfinite(lo[axis]) || !std::isfinite(hi[axis]) || !(lo[axis] <= hi[axis]))
            return Status(ErrorCode::InvalidArgument, "the scene bounds are empty or not finite");
    glm::dvec3 size = hi - lo;
    const double largest =
            std::max({size.x, size.y, size.z, 1e-6 * std::max(1.0, glm::length(lo))});
    Box box{lo, glm::max(size, glm::dvec3(1e-3 * largest))};
    box.min -= 0.5 * (box.size - size); // keep the centre where it was
    return box;
}

double frameTimeOf(std::int64_t frame, const PathGeneratorOptions& options) {
    return static_cast<double>(frame) / options.fps;
}

CameraKeyframe
keyframe(double time, const glm::dvec3& position, const glm::dvec3& forward, double fov) {
    CameraKeyframe k;
    k.time = time;
    k.position = position;
    k.orientation = lookOrientation(forward, kUp);
    k.fovDegrees = fov;
    return k;
}

} // namespace

Result<CameraPath> makeOrbitPath(const Bounds& bounds, const PathGeneratorOptions& options) {
    FF_ASSIGN_OR_RETURN(const Box box, fitBox(bounds, options));
    constexpr double kDistanceRadii = 2.5;
    constexpr double kElevation = 20.0 * std::numbers::pi / 180.0;
    constexpr double kStartAzimuth = 30.0 * std::numbers::pi / 180.0;
    const double distance = kDistanceRadii * 0.5 * box.diagonal();
    const glm::dvec3 center = box.center();
    std::vector<CameraKeyframe> keyframes;
    keyframes.reserve(static_cast<std::size_t>(options.frames));
    for (std::int64_t f = 0; f < options.frames; ++f) {
        const double azimuth = kStartAzimuth + 2.0 * std::numbers::pi * static_cast<double>(f) /
                                                       static_cast<double>(options.frames);
        const glm::dvec3 direction(
                std::cos(kElevation) * std::sin(azimuth),
                std::sin(kElevation),
                std::cos(kElevation) * std::cos(azimuth));
        const glm::dvec3 position = center + distance * direction;
        keyframes.push_back(
                keyframe(frameTimeOf(f, options), position, -direction, options.fovDegrees));
    }
    return CameraPath::create(
            std::move(keyframes), PathInterpolation::Spline, FrameSampling::rate(options.fps));
}

Result<CameraPath> makeFlythroughPath(const Bounds& bounds, const PathGeneratorOptions& options) {
    FF_ASSIGN_OR_RETURN(const Box box, fitBox(bounds, options));
    // Waypoints as (along, across) fractions of the box: along the longer horizontal axis, across
    // the other. The first lies outside; the interior ones weave from side to side.
    constexpr std::array<std::array<double, 2>, 7> kWaypoints = {{
            {-0.20, 0.50},
            {0.08, 0.50},
            {0.28, 0.26},
            {0.48, 0.72},
            {0.68, 0.28},
            {0.86, 0.66},
            {0.94, 0.45},
    }};
    const bool alongX = box.size.x >= box.size.z;
    const double height = 1.0 / 3.0;
    SplitMix64 random(options.seed);
    std::vector<glm::dvec3> points;
    for (std::size_t i = 0; i < kWaypoints.size(); ++i) {
        double across = kWaypoints[i][1];
        if (i >= 2) // jitter the weave, not the entry
            across = std::clamp(across + 0.16 * (random.uniform() - 0.5), 0.15, 0.85);
        const double along = kWaypoints[i][0];
        points.push_back(box.at(
                alongX ? glm::dvec3(along, height, across) : glm::dvec3(across, height, along)));
    }

    // The route: a spline through the waypoints over [0, 1], timed by chord length. Its
    // keyframes' orientations are placeholders; only positions are used.
    std::vector<CameraKeyframe> route;
    double length = 0.0;
    for (std::size_t i = 0; i < points.size(); ++i) {
        if (i > 0)
            length += glm::length(points[i] - points[i - 1]);
        CameraKeyframe k;
        k.time = length;
        k.position = points[i];
        route.push_back(k);
    }
    for (CameraKeyframe& k : route)
        k.time /= length;
    FF_ASSIGN_OR_RETURN(
            const CameraPath curve,
            CameraPath::create(std::move(route), PathInterpolation::Spline));

    // Constant speed: tabulate arc length along the route and invert it per frame.
    constexpr std::size_t kTable = 4096;
    std::vector<double> arc(kTable + 1, 0.0);
    glm::dvec3 previous = curve.pose(0.0).position;
    for (std::size_t j = 1; j <= kTable; ++j) {
        const glm::dvec3 p = curve.pose(static_cast<double>(j) / kTable).position;
        arc[j] = arc[j - 1] + glm::length(p - previous);
        previous = p;
    }
    const auto routeAt = [&arc](double fraction) {
        const double wanted = fraction * arc.back();
        const auto above = std::lower_bound(arc.begin() + 1, arc.end() - 1, wanted);
        const auto j = static_cast<std::size_t>(above - arc.begin());
        const double piece = arc[j] - arc[j - 1];
        const double within =
                piece > 0.0 ? std::clamp((wanted - arc[j - 1]) / piece, 0.0, 1.0) : 0.0;
        return (static_cast<double>(j - 1) + within) / kTable;
    };

    std::vector<CameraKeyframe> keyframes;
    keyframes.reserve(static_cast<std::size_t>(options.frames));
    const double last = static_cast<double>(std::max<std::int64_t>(options.frames - 1, 1));
    constexpr double kStep = 1e-4; // of the route, for the direction of travel
    for (std::int64_t f = 0; f < options.frames; ++f) {
        const double u = routeAt(static_cast<double>(f) / last);
        const glm::dvec3 position = curve.pose(u).position;
        glm::dvec3 ahead = curve.pose(std::min(u + kStep, 1.0)).position -
                           curve.pose(std::max(u - kStep, 0.0)).position;
        if (!(glm::dot(ahead, ahead) > 0.0))
            ahead = points.back() - points.front();
        keyframes.push_back(keyframe(frameTimeOf(f, options), position, ahead, options.fovDegrees));
    }
    return CameraPath::create(
            std::move(keyframes), PathInterpolation::Spline, FrameSampling::rate(options.fps));
}

Result<CameraPath> makeTeleportPath(const Bounds& bounds, const PathGeneratorOptions& options) {
    FF_ASSIGN_OR_RETURN(const Box box, fitBox(bounds, options));
    if (options.teleports < 1)
        return Status(ErrorCode::InvalidArgument, "teleports must be at least 1");
    if (options.frames < 2 * options.teleports)
        return Status(
                ErrorCode::InvalidArgument,
                "frames (" + std::to_string(options.frames) + ") must be at least 2 x teleports (" +
                        std::to_string(options.teleports) + ") so that each hold lasts 2 frames");
    const std::int64_t hold = options.frames / options.teleports;
    const double minJump = 0.3 * box.diagonal();
    SplitMix64 random(options.seed);
    const auto randomIn = [&random](double lo, double hi) {
        return glm::dvec3(
                lo + (hi - lo) * random.uniform(),
                lo + (hi - lo) * random.uniform(),
                lo + (hi - lo) * random.uniform());
    };

    std::vector<CameraKeyframe> keyframes;
    glm::dvec3 previous(0.0);
    for (std::int64_t jump = 0; jump < options.teleports; ++jump) {
        // Rejection sampling for a far enough jump, bounded so that it always ends: after 64 tries
        // the corner of the grown box farthest from the last position (>= 0.6 diagonals away).
        glm::dvec3 position = box.at(randomIn(-0.1, 1.1));
        for (int attempt = 0;
             jump > 0 && attempt < 64 && glm::length(position - previous) < minJump;
             ++attempt)
            position = box.at(randomIn(-0.1, 1.1));
        if (jump > 0 && glm::length(position - previous) < minJump)
            position = box.at(glm::mix(
                    glm::dvec3(1.1), glm::dvec3(-0.1), glm::greaterThan(previous, box.center())));
        glm::dvec3 forward = box.at(randomIn(0.2, 0.8)) - position;
        if (!(glm::length(forward) > 1e-3 * box.diagonal())) // next to the look-at point
            forward = glm::dvec3(0.0, 0.0, -1.0);

        const std::int64_t first = jump * hold;
        const std::int64_t last =
                jump + 1 == options.teleports ? options.frames - 1 : first + hold - 1;
        CameraKeyframe k =
                keyframe(frameTimeOf(first, options), position, forward, options.fovDegrees);
        k.name = "teleport " + std::to_string(jump);
        keyframes.push_back(k);
        k.time = frameTimeOf(last, options);
        keyframes.push_back(k);
        previous = position;
    }
    return CameraPath::create(
            std::move(keyframes), PathInterpolation::Linear, FrameSampling::rate(options.fps));
}

Result<CameraPath> makeWalkPath(const Bounds& bounds, const PathGeneratorOptions& options) {
    FF_RETURN_IF_ERROR(fitBox(bounds, options).status());
    std::vector<double> lengths;
    double total = 0.0;
    for (const std::vector<glm::dvec3>& leg : options.legs) {
        if (leg.size() < 2)
            return Status(ErrorCode::InvalidArgument, "every leg of a walk needs two points or more");
        double length = 0.0;
        for (std::size_t i = 1; i < leg.size(); ++i) {
            for (int axis = 0; axis < 3; ++axis)
                if (!std::isfinite(leg[i][axis]) || !std::isfinite(leg[i - 1][axis]))
                    return Status(ErrorCode::InvalidArgument, "a walk's points must be finite");
            length += glm::length(leg[i] - leg[i - 1]);
        }
        if (!(length > 0.0))
            return Status(ErrorCode::InvalidArgument, "a leg of a walk has no length");
        lengths.push_back(length);
        total += length;
    }
    if (lengths.empty())
        return Status(ErrorCode::InvalidArgument, "a walk needs at least one leg (--legs)");
    const auto legCount = static_cast<std::int64_t>(lengths.size());
    if (options.frames < 2 * legCount)
        return Status(ErrorCode::InvalidArgument, "a walk needs at least 2 frames a leg");

    // Frames shared out by length (2 at least a leg); each leg walked at constant speed, looking
    // a little ahead along it; from one leg's end to the next leg's start is a jump.
    std::vector<CameraKeyframe> keyframes;
    std::int64_t frame = 0;
    for (std::size_t l = 0; l < lengths.size(); ++l) {
        const std::vector<glm::dvec3>& leg = options.legs[l];
        const std::int64_t left = options.frames - frame;
        const auto legsLeft = static_cast<std::int64_t>(lengths.size() - l);
        const std::int64_t frames =
                l + 1 == lengths.size()
                        ? left
                        : std::clamp<std::int64_t>(
                                  static_cast<std::int64_t>(std::llround(static_cast<double>(options.frames) * lengths[l] / total)),
                                  2,
                                  left - 2 * (legsLeft - 1));
        const auto pointAt = [&leg](double distance) {
            for (std::size_t i = 1; i < leg.size(); ++i) {
                const double piece = glm::length(leg[i] - leg[i - 1]);
                if (distance <= piece || i + 1 == leg.size())
                    return glm::mix(leg[i - 1], leg[i], piece > 0.0 ? std::clamp(distance / piece, 0.0, 1.0) : 0.0);
                distance -= piece;
            }
            return leg.back();
        };
        const double ahead = std::min(options.legLookAhead, 0.5 * lengths[l]);
        for (std::int64_t f = 0; f < frames; ++f) {
            const double along = lengths[l] * static_cast<double>(f) / static_cast<double>(frames - 1);
            const glm::dvec3 position = pointAt(along);
            glm::dvec3 forward = pointAt(std::min(along + ahead, lengths[l])) - position;
            if (!(glm::dot(forward, forward) > 0.0))
                forward = leg.back() - leg[leg.size() - 2];
            CameraKeyframe k = keyframe(frameTimeOf(frame + f, options), position, forward, options.fovDegrees);
            if (f == 0)
                k.name = "leg " + std::to_string(l);
            keyframes.push_back(k);
        }
        frame += frames;
    }
    return CameraPath::create(std::move(keyframes), PathInterpolation::Linear, FrameSampling::rate(options.fps));
}

Result<std::vector<std::vector<glm::dvec3>>> parseWalkLegs(std::string_view text) {
    std::vector<std::vector<glm::dvec3>> legs;
    std::size_t start = 0;
    while (start <= text.size()) {
        const std::size_t end = std::min(text.find(';', start), text.size());
        std::vector<glm::dvec3> leg;
        std::istringstream points{std::string(text.substr(start, end - start))};
        std::string point;
        while (points >> point) {
            glm::dvec3 p(0.0);
            char comma1 = 0, comma2 = 0;
            std::istringstream coordinates(point);
            coordinates.imbue(std::locale::classic());
            if (!(coordinates >> p.x >> comma1 >> p.y >> comma2 >> p.z) || comma1 != ',' || comma2 != ',' ||
                !coordinates.eof())
                return Status(ErrorCode::InvalidArgument, "walk point '" + point + "' is not x,y,z");
            leg.push_back(p);
        }
        if (!leg.empty())
            legs.push_back(std::move(leg));
        start = end + 1;
    }
    return legs;
}

std::string formatWalkLegs(const std::vector<std::vector<glm::dvec3>>& legs) {
    std::ostringstream out;
    out.imbue(std::locale::classic());
    out.precision(17);
    for (std::size_t l = 0; l < legs.size(); ++l) {
        if (l > 0)
            out << "; ";
        for (std::size_t i = 0; i < legs[l].size(); ++i)
            out << (i > 0 ? " " : "") << legs[l][i].x << ',' << legs[l][i].y << ',' << legs[l][i].z;
    }
    return out.str();
}

} // namespace ff::runtime
