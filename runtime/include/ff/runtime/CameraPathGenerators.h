#pragma once

// Camera paths fitted to a scene's bounds, for walk-throughs and paging-behaviour tests. +Y is up
// (as in glTF and Camera::orbit). Every generator writes one keyframe per frame at time
// frame / fps, so frameTime(i) of the result lands exactly on keyframe i: what each frame sees is
// spelled out in the path file rather than left to interpolation.

#include <ff/runtime/Camera.h>
#include <ff/runtime/CameraPath.h>
#include <ff/storage/Status.h>

#include <glm/glm.hpp>

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace ff::runtime {

struct PathGeneratorOptions {
    std::int64_t frames = 300;  ///< frames in the path, >= 1
    double fps = 30.0;          ///< > 0; the path lasts (frames - 1) / fps seconds
    std::uint64_t seed = 1;     ///< flythrough waypoints, teleport positions (splitmix64)
    std::int64_t teleports = 8; ///< teleports: number of jumps, >= 1 and <= frames / 2
    double fovDegrees = 45.0;   ///< vertical field of view, in (0, 180)
    /** walk: polylines in the scene file's frame (as --eye); the camera jumps between them. */
    std::vector<std::vector<glm::dvec3>> legs;
    /** walk: how far ahead along a leg the camera looks, scene units. */
    double legLookAhead = 10.0;
};

/**
 * A full circle about the vertical axis through the bounds' centre, 2.5 bounding-sphere radii
 * away and 20 degrees above the horizon, looking at the centre; starts at azimuth 30 degrees (as
 * the default `farfield render` view) and stops one step short of closing the circle.
 * Errors: InvalidArgument for bad options or empty/non-finite bounds.
 */
[[nodiscard]] Result<CameraPath>
makeOrbitPath(const Bounds& bounds, const PathGeneratorOptions& options = {});

/**
 * A walk through the scene: starts outside the bounds, enters across the face at -X (or -Z when
 * the scene is deeper than wide) and weaves through the interior at a third of the bounds'
 * height along the longer horizontal axis, looking along the direction of travel at constant
 * speed. The camera crosses into the bounds within the first fifth of the path and stays inside
 * to the end. The seed moves the waypoints sideways. Errors as makeOrbitPath().
 */
[[nodiscard]] Result<CameraPath>
makeFlythroughPath(const Bounds& bounds, const PathGeneratorOptions& options = {});

/**
 * `teleports` holds, each a jump to a random position in the bounds grown by 10% per side,
 * looking at a random point of the bounds' central region, held for frames / teleports frames
 * (the last hold takes the remainder). Consecutive positions are at least 0.3 bounds diagonals
 * apart. Linear interpolation; each hold is a pair of equal keyframes and the jump happens
 * between two consecutive frames. Deterministic for a seed. Errors as makeOrbitPath(), and
 * InvalidArgument if frames < 2 * teleports.
 */
[[nodiscard]] Result<CameraPath>
makeTeleportPath(const Bounds& bounds, const PathGeneratorOptions& options = {});

/**
 * A walk-through given by its legs (options.legs: polylines, e.g. along a street at eye
 * height): each leg walked at constant speed, looking ahead along it; the frames are shared out
 * by length (two at least a leg), and from one leg to the next the camera jumps, a teleport
 * between two consecutive frames. Errors: InvalidArgument for no legs, a leg of fewer than two
 * points or no length, non-finite points, fewer than 2 frames a leg, and as makeOrbitPath().
 */
[[nodiscard]] Result<CameraPath>
makeWalkPath(const Bounds& bounds, const PathGeneratorOptions& options);

/** "x,y,z x,y,z; x,y,z x,y,z": legs separated by ';', points by spaces. InvalidArgument naming
 *  the bad point. */
[[nodiscard]] Result<std::vector<std::vector<glm::dvec3>>> parseWalkLegs(std::string_view text);
/** The text parseWalkLegs() reads (numbers round-trip). */
std::string formatWalkLegs(const std::vector<std::vector<glm::dvec3>>& legs);

} // namespace ff::runtime
