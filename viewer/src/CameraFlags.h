#pragma once

// The camera flags of render and view (--camera, --eye, --orbit distance, --path, ...), filling a
// runtime::CameraOptions.

#include <ff/runtime/CameraOptions.h>

#include <CLI/CLI.hpp>

namespace ff::viewer {

void addCameraOptions(CLI::App& app, runtime::CameraOptions& options);

} // namespace ff::viewer
