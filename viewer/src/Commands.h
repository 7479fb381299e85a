#pragma once

#include <ff/storage/Status.h>

#include <CLI/CLI.hpp>

#include <functional>

namespace ff::viewer {

/** A verb's entry point, run after its flags are parsed; returns the process exit code. */
using CommandRunner = std::function<int()>;

/** Each verb adds its subcommand with its flags and returns how to run it. */
CommandRunner addBuildCommand(CLI::App& app);
CommandRunner addRenderCommand(CLI::App& app);
CommandRunner addCheckCommand(CLI::App& app);
CommandRunner addBenchCommand(CLI::App& app);
CommandRunner addReplayCommand(CLI::App& app);
CommandRunner addPathCommand(CLI::App& app);
CommandRunner addViewCommand(CLI::App& app);
CommandRunner addStatsCommand(CLI::App& app);

/** Prints "farfield <verb>: <message>" to stderr; returns the exit code for the error. */
int reportError(const char* verb, const ff::Status& status);

} // namespace ff::viewer
