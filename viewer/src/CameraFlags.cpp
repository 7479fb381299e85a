#include "CameraFlags.h"

namespace ff::viewer {

void addCameraOptions(CLI::App& app, runtime::CameraOptions& options) {
    app.add_option("--camera", options.camera, "Camera stored from the source glTF, e.g. gltf:0");
    app.add_option("--eye", options.eye, "Camera position x,y,z (with --target)");
    app.add_option("--target", options.target, "Point looked at x,y,z (with --eye)");
    app.add_option("--up", options.up, "Up direction x,y,z")->capture_default_str();
    app.add_option("--fov", options.fovDegrees, "Vertical field of view, degrees")
            ->capture_default_str();
    app.add_option(
               "--distance",
               options.distance,
               "Orbit camera: distance from the centre in scene radii")
            ->capture_default_str();
    app.add_option("--azimuth", options.azimuth, "Orbit camera: degrees about +Y, from +Z")
            ->capture_default_str();
    app.add_option("--elevation", options.elevation, "Orbit camera: degrees above the horizon")
            ->capture_default_str();
    app.add_option(
            "--path", options.path, "Camera path JSON (farfield path ...); its frame --path-frame");
    app.add_option("--path-frame", options.pathFrame, "Frame of --path to use, from 0 (default 0)");
}

} // namespace ff::viewer
