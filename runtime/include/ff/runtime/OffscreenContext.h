#pragma once

#include <ff/storage/Status.h>

#include <memory>
#include <string>

namespace ff::runtime {

/**
 * A headless OpenGL 4.5 core context (OSMesa, llvmpipe), current on the creating thread for its
 * lifetime. Rendering goes to framebuffer objects; the context's own buffer is a token 1x1.
 */
class OffscreenContext {
public:
    /** Errors: Unsupported when OSMesa cannot give a 4.5 core context. */
    [[nodiscard]] static Result<std::unique_ptr<OffscreenContext>> create();
    ~OffscreenContext();
    OffscreenContext(const OffscreenContext&) = delete;
    OffscreenContext& operator=(const OffscreenContext&) = delete;

    /** "4.5 (Core Profile) Mesa 22.3.6 / llvmpipe (...)" */
    std::string description() const;

private:
    struct Impl;
    explicit OffscreenContext(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> mImpl;
};

} // namespace ff::runtime
