#pragma once

#include <ff/runtime/Image.h>
#include <ff/storage/Status.h>

#include <filesystem>

namespace ff::viewer {

/** Writes `image` with OpenImageIO; the format follows the extension (.png, .exr, .tif, ...).
 *  8-bit formats get sRGB, EXR linear half floats. RGB, plus coverage as alpha if asked. */
[[nodiscard]] Status writeImage(
        const std::filesystem::path& path, const runtime::Image& image, bool withCoverage = false);

/** Ok if writeImage() knows the format of `path`'s extension; writes nothing. */
[[nodiscard]] Status checkImageFormat(const std::filesystem::path& path);

/** Reads an RGBA8 image (for comparisons in tests and benches). */
[[nodiscard]] Result<runtime::Image> readImage(const std::filesystem::path& path);

} // namespace ff::viewer
