#include <ff/runtime/OffscreenContext.h>

#include "GlHeaders.h"

#include <GL/osmesa.h> // types and enums only; the library is opened with dlopen

#include <dlfcn.h>

#include <array>

namespace ff::runtime {

namespace {

using CreateContextAttribsFn = OSMesaContext (*)(const int*, OSMesaContext);
using MakeCurrentFn = GLboolean (*)(OSMesaContext, void*, GLenum, GLsizei, GLsizei);
using DestroyContextFn = void (*)(OSMesaContext);
using GetProcAddressFn = OSMESAproc (*)(const char*);

// glad's loader callback cannot carry state; the resolver is set just before loading.
GetProcAddressFn sGetProcAddress = nullptr; // written and read on the creating thread only

GLADapiproc loadGlFunction(const char* name) { return reinterpret_cast<GLADapiproc>(sGetProcAddress(name)); }

} // namespace

struct OffscreenContext::Impl {
    void* library = nullptr;
    DestroyContextFn destroy = nullptr;
    OSMesaContext context = nullptr;
    std::array<unsigned char, 4> buffer{};

    ~Impl() {
        if (context && destroy)
            destroy(context);
        // The library stays loaded: LLVM inside it does not support being unloaded.
    }
};

OffscreenContext::OffscreenContext(std::unique_ptr<Impl> impl) : mImpl(std::move(impl)) {}
OffscreenContext::~OffscreenContext() = default;

Result<std::unique_ptr<OffscreenContext>> OffscreenContext::create() {
    auto impl = std::make_unique<Impl>();
    impl->library = dlopen("libOSMesa.so.8", RTLD_NOW | RTLD_LOCAL);
    if (!impl->library)
        return Status(ErrorCode::Unsupported, std::string("cannot load OSMesa (package libosmesa6): ") + dlerror());
    const auto create = reinterpret_cast<CreateContextAttribsFn>(dlsym(impl->library, "OSMesaCreateContextAttribs"));
    const auto makeCurrent = reinterpret_cast<MakeCurrentFn>(dlsym(impl->library, "OSMesaMakeCurrent"));
    impl->destroy = reinterpret_cast<DestroyContextFn>(dlsym(impl->library, "OSMesaDestroyContext"));
    const auto getProcAddress = reinterpret_cast<GetProcAddressFn>(dlsym(impl->library, "OSMesaGetProcAddress"));
    if (!create || !makeCurrent || !impl->destroy || !getProcAddress)
        return Status(ErrorCode::Unsupported, "libOSMesa lacks the OSMesa 11.2 context API");

    const std::array<int, 11> attributes = {
            OSMESA_FORMAT, OSMESA_RGBA, OSMESA_DEPTH_BITS, 24, OSMESA_PROFILE, OSMESA_CORE_PROFILE,
            OSMESA_CONTEXT_MAJOR_VERSION, 4, OSMESA_CONTEXT_MINOR_VERSION, 5, 0};
    impl->context = create(attributes.data(), nullptr);
    if (!impl->context)
        return Status(ErrorCode::Unsupported, "OSMesa could not create an OpenGL 4.5 core context");
    if (!makeCurrent(impl->context, impl->buffer.data(), GL_UNSIGNED_BYTE, 1, 1))
        return Status(ErrorCode::Unsupported, "OSMesa could not make its context current");
    sGetProcAddress = getProcAddress;
    const int version = gladLoadGL(loadGlFunction);
    if (GLAD_VERSION_MAJOR(version) * 10 + GLAD_VERSION_MINOR(version) < 45)
        return Status(ErrorCode::Unsupported, "OpenGL 4.5 core is not available through OSMesa");
    return std::unique_ptr<OffscreenContext>(new OffscreenContext(std::move(impl)));
}

std::string OffscreenContext::description() const {
    const auto* version = reinterpret_cast<const char*>(glGetString(GL_VERSION));
    const auto* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
    return std::string(version ? version : "?") + " / " + (renderer ? renderer : "?");
}

} // namespace ff::runtime
