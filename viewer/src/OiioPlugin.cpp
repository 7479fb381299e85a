// The OpenImageIO side of image I/O, built as its own shared library (ff_oiio) and loaded on
// first use by ImageOutput.cpp: OpenImageIO's dependency chain costs ~130 MB of resident
// memory at load time, which `farfield build` must not pay against its --memory-budget.

#include "OiioPlugin.h"

#include <ff/runtime/Image.h>

#include <ff/storage/VertexCodec.h>

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

namespace ff::viewer {

namespace {

Status writeImageImpl(const std::filesystem::path& path, const runtime::Image& image, bool withCoverage) {
    auto out = OIIO::ImageOutput::create(path.string());
    if (!out)
        return Status(ErrorCode::InvalidArgument, "cannot write " + path.string() + ": " + OIIO::geterror());
    std::string extension = path.extension().string();
    std::transform(extension.begin(), extension.end(), extension.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    const bool linearFloat = extension == ".exr" || extension == ".hdr";
    const int channels = withCoverage ? 4 : 3;
    OIIO::ImageSpec spec(image.width, image.height, channels, linearFloat ? OIIO::TypeDesc::HALF : OIIO::TypeDesc::UINT8);
    spec.attribute("oiio:ColorSpace", linearFloat ? "Linear" : "sRGB");
    if (!out->open(path.string(), spec))
        return Status(ErrorCode::IoError, "cannot write " + path.string() + ": " + out->geterror());
    // Strides let OIIO pick 3 of the 4 channels without a copy.
    const OIIO::stride_t pixelStride = 4 * sizeof(float);
    bool ok = false;
    if (linearFloat) {
        std::vector<float> pixels(image.rgba.size());
        for (std::size_t i = 0; i < image.rgba.size(); ++i)
            pixels[i] = (i % 4 == 3) ? image.rgba[i] / 255.0f : storage::srgb8ToLinear(image.rgba[i]);
        ok = out->write_image(OIIO::TypeDesc::FLOAT, pixels.data(), pixelStride);
    } else {
        ok = out->write_image(OIIO::TypeDesc::UINT8, image.rgba.data(), 4);
    }
    if (!ok || !out->close())
        return Status(ErrorCode::IoError, "cannot write " + path.string() + ": " + out->geterror());
    return Status::ok();
}

Result<runtime::Image> readImageImpl(const std::filesystem::path& path) {
    auto in = OIIO::ImageInput::open(path.string());
    if (!in)
        return Status(ErrorCode::NotFound, "cannot read " + path.string() + ": " + OIIO::geterror());
    const OIIO::ImageSpec& spec = in->spec();
    runtime::Image image;
    image.width = spec.width;
    image.height = spec.height;
    image.rgba.assign(static_cast<std::size_t>(spec.width) * static_cast<std::size_t>(spec.height) * 4, 255);
    std::vector<std::uint8_t> pixels(static_cast<std::size_t>(spec.width) * static_cast<std::size_t>(spec.height) *
                                     static_cast<std::size_t>(spec.nchannels));
    if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::UINT8, pixels.data()))
        return Status(ErrorCode::Corrupt, "cannot read " + path.string() + ": " + in->geterror());
    const auto channels = static_cast<std::size_t>(spec.nchannels);
    for (std::size_t p = 0; p < pixels.size() / channels; ++p)
        for (std::size_t c = 0; c < std::min<std::size_t>(channels, 4); ++c)
            image.rgba[p * 4 + c] = pixels[p * channels + c];
    return image;
}

} // namespace

} // namespace ff::viewer

extern "C" {

int ffOiioPluginVersion() { return ff::viewer::kOiioPluginVersion; }

ff::Status* ffOiioWriteImage(const char* path, const ff::runtime::Image* image, int withCoverage) {
    return new ff::Status(ff::viewer::writeImageImpl(path, *image, withCoverage != 0));
}

ff::Status* ffOiioReadImage(const char* path, ff::runtime::Image* out) {
    ff::Result<ff::runtime::Image> image = ff::viewer::readImageImpl(path);
    if (!image)
        return new ff::Status(image.status());
    *out = std::move(image).value();
    return new ff::Status();
}

ff::Status* ffOiioCheckImageFormat(const char* path) {
    if (!OIIO::ImageOutput::create(path))
        return new ff::Status(ff::ErrorCode::InvalidArgument,
                              std::string("cannot write ") + path + ": no image format for its extension");
    return new ff::Status();
}

void ffOiioFreeStatus(ff::Status* status) { delete status; }

} // extern "C"

