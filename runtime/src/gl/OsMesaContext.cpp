#include <ff/runtime/OffscreenContext.h>

#include "GlHeaders.h"

#include <GL/osmesa.h>

#include <array>

namespace ff::runtime {

struct OffscreenContext::Impl {
    OSMesaContext context = nullptr;
    std::array<unsigned char, 4> buffer{};
};

OffscreenContext::OffscreenContext(std::unique_ptr<Impl> impl) : mImpl(std::move(impl)) {}

OffscreenContext::~OffscreenContext() {
    if (mImpl && mImpl->context)
        OSMesaDestroyContext(mImpl->context);
}

Result<std::unique_ptr<OffscreenContext>> OffscreenContext::create() {
    const std::array<int, 13> attributes = {
            OSMESA_FORMAT, OSMESA_RGBA, OSMESA_DEPTH_BITS, 24, OSMESA_PROFILE, OSMESA_CORE_PROFILE,
            OSMESA_CONTEXT_MAJOR_VERSION, 4, OSMESA_CONTEXT_MINOR_VERSION, 5, 0, 0, 0};
    auto impl = std::make_unique<Impl>();
    impl->context = OSMesaCreateContextAttribs(attributes.data(), nullptr);
    if (!impl->context)
        return Status(ErrorCode::Unsupported, "OSMesa could not create an OpenGL 4.5 core context");
    if (!OSMesaMakeCurrent(impl->context, impl->buffer.data(), GL_UNSIGNED_BYTE, 1, 1)) {
        OSMesaDestroyContext(impl->context);
        return Status(ErrorCode::Unsupported, "OSMesa could not make its context current");
    }
    return std::unique_ptr<OffscreenContext>(new OffscreenContext(std::move(impl)));
}

std::string OffscreenContext::description() const {
    const auto* version = reinterpret_cast<const char*>(glGetString(GL_VERSION));
    const auto* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
    return std::string(version ? version : "?") + " / " + (renderer ? renderer : "?");
}

} // namespace ff::runtime
