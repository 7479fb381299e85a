#pragma once

// The flags several verbs share (render, replay, view, stats), each defined once: the same name,
// help text, default display and check everywhere.

#include <ff/runtime/FrameContext.h>

#include <CLI/CLI.hpp>

#include <cstdint>
#include <string>

namespace ff::viewer {

extern const char* const kEpsilonHelp;

CLI::Option* addEpsilonOption(CLI::App& cmd, float& epsilon);
CLI::Option* addMethodOption(CLI::App& cmd, std::string& method);
CLI::Option* addCubeDrawOption(CLI::App& cmd, std::string& cubeDraw);
/** `--representation auto|cube|simplified|splats` (runtime::Representation). */
CLI::Option* addRepresentationOption(CLI::App& cmd, runtime::Representation& representation);
/** `--splat-size 1|2|3` and `--splat-shape round|square` (runtime::SplatStyle). */
void addSplatOptions(CLI::App& cmd, runtime::SplatStyle& style);
CLI::Option* addCubeAnisotropyOption(CLI::App& cmd, float& anisotropy);
CLI::Option* addGpuBudgetOption(CLI::App& cmd, std::string& gpuBudget);
CLI::Option* addGpuUploadsOption(CLI::App& cmd, std::uint32_t& uploads);
CLI::Option* addBackgroundOption(CLI::App& cmd, std::string& background);

/** --occlusion off|on, --occlusion-backend queries|hzb and --occlusion-queries N, straight into the frame's options; with
 *  `oracle`, --occlusion oracle too (StreamingSession::renderOracle, for benchmarks). */
void addOcclusionOptions(CLI::App& cmd, runtime::OcclusionOptions& occlusion, bool* oracle = nullptr);

} // namespace ff::viewer
