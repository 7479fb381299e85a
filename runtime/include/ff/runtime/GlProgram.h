#pragma once

// The runtime's GL layer as far as other GL code in the process needs it (the viewer's HUD):
// one way to build a shader program, with the compiler's log in the error.

#include <ff/storage/Status.h>

#include <cstdint>
#include <initializer_list>

namespace ff::runtime {

/**
 * Compiles and links a GL program: `vertexSources` are concatenated as glShaderSource does with
 * several strings, `fragmentSource` is one. Returns the program's name (a GLuint). Needs a
 * current GL context. Errors: Internal with the compile or link log.
 */
[[nodiscard]] Result<std::uint32_t>
linkGlProgram(std::initializer_list<const char*> vertexSources, const char* fragmentSource);

} // namespace ff::runtime
