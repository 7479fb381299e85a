#pragma once

// The C interface between farfield and its OpenImageIO plugin (libff_oiio.so). Both sides are
// built from this tree with the same compiler, so C++ types cross it; the version guards
// against a stale plugin beside a newer executable.

#include <ff/runtime/Image.h>
#include <ff/storage/Status.h>

namespace ff::viewer {
inline constexpr int kOiioPluginVersion = 2;
} // namespace ff::viewer

extern "C" {
using FfOiioPluginVersionFn = int (*)();
using FfOiioWriteImageFn = ff::Status* (*)(const char* path, const ff::runtime::Image* image, int withCoverage);
using FfOiioReadImageFn = ff::Status* (*)(const char* path, ff::runtime::Image* out);
using FfOiioCheckImageFormatFn = ff::Status* (*)(const char* path);
using FfOiioFreeStatusFn = void (*)(ff::Status* status);

int ffOiioPluginVersion();
ff::Status* ffOiioWriteImage(const char* path, const ff::runtime::Image* image, int withCoverage);
ff::Status* ffOiioReadImage(const char* path, ff::runtime::Image* out);
/** Ok if OpenImageIO has a writer for the path's extension; opens nothing. */
ff::Status* ffOiioCheckImageFormat(const char* path);
void ffOiioFreeStatus(ff::Status* status);
}
