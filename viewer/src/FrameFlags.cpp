#include "FrameFlags.h"

#include <ff/runtime/Selection.h>

namespace ff::viewer {

const char* const kEpsilonHelp = "A cell whose box covers less than epsilon^2 pixels on screen is "
                                 "drawn as its color cube (0: all geometry)";

CLI::Option* addEpsilonOption(CLI::App& cmd, float& epsilon) {
    return cmd.add_option("--epsilon", epsilon, kEpsilonHelp)->capture_default_str();
}

CLI::Option* addMethodOption(CLI::App& cmd, std::string& method) {
    // Checked by the verb, which names the flag in its own error.
    return cmd
            .add_option("--method", method, "hierarchical or full (every triangle, no hierarchy)")
            ->capture_default_str();
}

CLI::Option* addCubeDrawOption(CLI::App& cmd, std::string& cubeDraw) {
    return cmd
            .add_option(
                    "--cube-draw",
                    cubeDraw,
                    "Color cubes as faces, points (one area-weighted point per cube) or auto "
                    "(points when "
                    "epsilon <= 2)")
            ->check(CLI::IsMember(runtime::cubeStyleNames()))
            ->capture_default_str();
}

CLI::Option* addRepresentationOption(CLI::App& cmd, runtime::Representation& representation) {
    return cmd
            .add_option_function<std::string>(
                    "--representation",
                    [&representation](const std::string& name) {
                        representation = runtime::parseRepresentation(name).value_or(runtime::Representation::Auto);
                    },
                    "What a cell may be drawn as instead of its subtree: auto (its cube below epsilon pixels, "
                    "else its stand-in where its error is below epsilon pixels; format 2 built with "
                    "--stand-ins or --splats), cube (never a stand-in), simplified or splats (that kind of "
                    "stand-in also where auto draws the cube; a cell without one is refined)")
            ->check(CLI::IsMember({"auto", "cube", "simplified", "splats"}))
            ->default_str(runtime::representationName(representation));
}

void addSplatOptions(CLI::App& cmd, runtime::SplatStyle& style) {
    cmd.add_option("--splat-size", style.pixels,
                   "Largest splat diameter in pixels (1-3): a cell's splats are drawn where this covers twice their "
                   "error on screen, and at twice that error")
            ->check(CLI::Range(1.0f, 3.0f))
            ->capture_default_str();
    cmd.add_option_function<std::string>(
               "--splat-shape", [&style](const std::string& shape) { style.round = shape == "round"; },
               "Splats as discs (round) or squares (square)")
            ->check(CLI::IsMember({"round", "square"}))
            ->default_str(style.round ? "round" : "square");
}

CLI::Option* addCubeAnisotropyOption(CLI::App& cmd, float& anisotropy) {
    return cmd
            .add_option(
                    "--cube-anisotropy",
                    anisotropy,
                    "Refuse colour cubes whose coverage differs more than this between axes (0..1; "
                    "1 = never)")
            ->check(CLI::Range(0.0f, 1.0f))
            ->capture_default_str();
}

CLI::Option* addGpuBudgetOption(CLI::App& cmd, std::string& gpuBudget) {
    return cmd.add_option("--gpu-budget", gpuBudget, "GPU memory for geometry pages")
            ->capture_default_str();
}

CLI::Option* addGpuUploadsOption(CLI::App& cmd, std::uint32_t& uploads) {
    return cmd
            .add_option(
                    "--gpu-uploads-per-frame",
                    uploads,
                    "Geometry pages uploaded to the GPU per frame at most; cells over it are drawn "
                    "as cubes "
                    "this frame (0: no bound)")
            ->capture_default_str();
}

CLI::Option* addBackgroundOption(CLI::App& cmd, std::string& background) {
    return cmd.add_option("--background", background, "Background colour, linear r,g,b")
            ->capture_default_str();
}

void addOcclusionOptions(CLI::App& cmd, runtime::OcclusionOptions& occlusion, bool* oracle) {
    cmd.add_option_function<std::string>(
               "--occlusion",
               [&occlusion, oracle](const std::string& mode) {
                   occlusion.enabled = mode == "on";
                   if (oracle)
                       *oracle = mode == "oracle";
               },
               oracle ? "Occlusion culling: test boxes against what is drawn, front to back, before "
                        "drawing what they hold (on), not (off), or draw exactly what an ID pass "
                        "found visible (oracle: the bound of what culling can save; every page mapped)"
                      : "Occlusion culling: test boxes against what is drawn, front to back, before "
                        "drawing what they hold (on) or not (off)")
            ->check(oracle ? CLI::IsMember({"off", "on", "oracle"}) : CLI::IsMember({"off", "on"}))
            ->default_str(occlusion.enabled ? "on" : "off");
    cmd.add_option_function<std::string>(
               "--occlusion-backend",
               [&occlusion](const std::string& name) {
                   occlusion.backend = runtime::parseOcclusionBackend(name).value_or(runtime::OcclusionBackend::Queries);
               },
               "How occlusion tests are answered: hardware queries, answered late (queries), or a "
               "max-depth pyramid of the depth read back, tested on the CPU (hzb)")
            ->check(CLI::IsMember({"queries", "hzb"}))
            ->default_str(runtime::occlusionBackendName(occlusion.backend));
    cmd.add_option_function<std::string>(
               "--cube-occluders",
               [&occlusion](const std::string& mode) { occlusion.cubesOcclude = mode == "on"; },
               "With occlusion culling: color cubes occlude too, drawn front to back to depth where "
               "the opacity over a pixel reaches 1 - the opacity threshold")
            ->check(CLI::IsMember({"on", "off"}))
            ->default_str(occlusion.cubesOcclude ? "on" : "off");
    cmd.add_option(
               "--opacity-threshold",
               occlusion.opacityThreshold,
               "Aggregate opacity: translucent cubes occlude together once at most this share of "
               "light shows through a pixel (0: only faces of alpha 1 occlude, exact; above 0: "
               "approximate)")
            ->check(CLI::Range(0.0f, 0.5f))
            ->capture_default_str();
    cmd.add_option(
               "--occlusion-queries",
               occlusion.queryBudget,
               "Occlusion tests a frame may issue at most (past it, untested nodes are drawn)")
            ->check(CLI::PositiveNumber)
            ->capture_default_str();
    cmd.add_option(
               "--occlusion-min-hidden",
               occlusion.minHiddenShare,
               "With occlusion culling: after a frame whose tests hid less than this share of what "
               "it drew (estimated), the next 8 frames go without tests, as frustum culling draws "
               "them, unless the camera jumps (0: test every frame; measured no faster yet, "
               "docs/methods.md §9)")
            ->check(CLI::Range(0.0f, 1.0f))
            ->capture_default_str();
}

} // namespace ff::viewer
