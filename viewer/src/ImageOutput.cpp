#include "ImageOutput.h"

#include "OiioPlugin.h"

#include <dlfcn.h>

#include <filesystem>
#include <memory>
#include <string>
#include <system_error>

namespace ff::viewer {

namespace {

struct Plugin {
    FfOiioWriteImageFn write = nullptr;
    FfOiioReadImageFn read = nullptr;
    FfOiioCheckImageFormatFn checkFormat = nullptr;
    FfOiioFreeStatusFn freeStatus = nullptr;
    Status status;
};

// Loaded once per process on first use; the handle is never closed (process lifetime).
const Plugin& plugin() {
    static const Plugin loaded = [] {
        Plugin p;
        // Beside the executable. By full path: a bare name would be searched with the RUNPATH
        // of dlopen's caller, which is the sanitizer runtime in ASan builds, not farfield.
        std::error_code error;
        const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", error);
        void* handle = error ? nullptr : dlopen((exe.parent_path() / "libff_oiio.so").c_str(), RTLD_NOW | RTLD_LOCAL);
        if (!handle) // where this tree built it: programs linking the viewer elsewhere (tests)
            handle = dlopen(FF_OIIO_PLUGIN_BUILD_PATH, RTLD_NOW | RTLD_LOCAL);
        if (!handle) // the executable's RUNPATH ($ORIGIN), e.g. where /proc is not mounted
            handle = dlopen("libff_oiio.so", RTLD_NOW | RTLD_LOCAL);
        if (!handle) {
            p.status = Status(ErrorCode::Unsupported, std::string("cannot load the image plugin: ") + dlerror());
            return p;
        }
        const auto version = reinterpret_cast<FfOiioPluginVersionFn>(dlsym(handle, "ffOiioPluginVersion"));
        p.write = reinterpret_cast<FfOiioWriteImageFn>(dlsym(handle, "ffOiioWriteImage"));
        p.read = reinterpret_cast<FfOiioReadImageFn>(dlsym(handle, "ffOiioReadImage"));
        p.checkFormat = reinterpret_cast<FfOiioCheckImageFormatFn>(dlsym(handle, "ffOiioCheckImageFormat"));
        p.freeStatus = reinterpret_cast<FfOiioFreeStatusFn>(dlsym(handle, "ffOiioFreeStatus"));
        if (!version || !p.write || !p.read || !p.checkFormat || !p.freeStatus || version() != kOiioPluginVersion)
            p.status = Status(ErrorCode::Unsupported, "libff_oiio.so does not match this farfield");
        return p;
    }();
    return loaded;
}

Status take(const Plugin& p, Status* raw) {
    Status status = *raw;
    p.freeStatus(raw);
    return status;
}

} // namespace

Status writeImage(const std::filesystem::path& path, const runtime::Image& image, bool withCoverage) {
    const Plugin& p = plugin();
    if (!p.status.isOk())
        return p.status;
    return take(p, p.write(path.c_str(), &image, withCoverage ? 1 : 0));
}

Status checkImageFormat(const std::filesystem::path& path) {
    const Plugin& p = plugin();
    if (!p.status.isOk())
        return p.status;
    return take(p, p.checkFormat(path.c_str()));
}

Result<runtime::Image> readImage(const std::filesystem::path& path) {
    const Plugin& p = plugin();
    if (!p.status.isOk())
        return p.status;
    runtime::Image image;
    FF_RETURN_IF_ERROR(take(p, p.read(path.c_str(), &image)));
    return image;
}

} // namespace ff::viewer
