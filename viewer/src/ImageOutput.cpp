#include "ImageOutput.h"

#include "OiioPlugin.h"

#include <dlfcn.h>

#include <memory>
#include <string>

namespace ff::viewer {

namespace {

struct Plugin {
    FfOiioWriteImageFn write = nullptr;
    FfOiioReadImageFn read = nullptr;
    FfOiioFreeStatusFn freeStatus = nullptr;
    Status status;
};

// Loaded once per process on first use; the handle is never closed (process lifetime).
const Plugin& plugin() {
    static const Plugin loaded = [] {
        Plugin p;
        // The executable's RUNPATH ($ORIGIN) finds the plugin beside it.
        void* handle = dlopen("libff_oiio.so", RTLD_NOW | RTLD_LOCAL);
        if (!handle) {
            p.status = Status(ErrorCode::Unsupported, std::string("cannot load the image plugin: ") + dlerror());
            return p;
        }
        const auto version = reinterpret_cast<FfOiioPluginVersionFn>(dlsym(handle, "ffOiioPluginVersion"));
        p.write = reinterpret_cast<FfOiioWriteImageFn>(dlsym(handle, "ffOiioWriteImage"));
        p.read = reinterpret_cast<FfOiioReadImageFn>(dlsym(handle, "ffOiioReadImage"));
        p.freeStatus = reinterpret_cast<FfOiioFreeStatusFn>(dlsym(handle, "ffOiioFreeStatus"));
        if (!version || !p.write || !p.read || !p.freeStatus || version() != kOiioPluginVersion)
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

Result<runtime::Image> readImage(const std::filesystem::path& path) {
    const Plugin& p = plugin();
    if (!p.status.isOk())
        return p.status;
    runtime::Image image;
    FF_RETURN_IF_ERROR(take(p, p.read(path.c_str(), &image)));
    return image;
}

} // namespace ff::viewer
