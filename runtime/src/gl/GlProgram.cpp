#include "GlHeaders.h"

#include <ff/runtime/GlProgram.h>

#include <string>

namespace ff::runtime {

namespace {

// `sources` are concatenated, as glShaderSource does with several strings.
Result<GLuint> compileShader(GLenum type, std::initializer_list<const char*> sources) {
    const GLuint shader = glCreateShader(type);
    glShaderSource(shader, static_cast<GLsizei>(sources.size()), sources.begin(), nullptr);
    glCompileShader(shader);
    GLint ok = 0;
    glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        std::string log(4096, '\0');
        GLsizei length = 0;
        glGetShaderInfoLog(shader, static_cast<GLsizei>(log.size()), &length, log.data());
        log.resize(static_cast<std::size_t>(length));
        glDeleteShader(shader);
        return Status(ErrorCode::Internal, "shader compilation failed: " + log);
    }
    return shader;
}

} // namespace

Result<std::uint32_t>
linkGlProgram(std::initializer_list<const char*> vertexSources, const char* fragmentSource) {
    FF_ASSIGN_OR_RETURN(const GLuint vs, compileShader(GL_VERTEX_SHADER, vertexSources));
    Result<GLuint> compiledFs = compileShader(GL_FRAGMENT_SHADER, {fragmentSource});
    if (!compiledFs) {
        glDeleteShader(vs);
        return compiledFs.status();
    }
    const GLuint fs = *compiledFs;
    const GLuint program = glCreateProgram();
    glAttachShader(program, vs);
    glAttachShader(program, fs);
    glLinkProgram(program);
    glDeleteShader(vs);
    glDeleteShader(fs);
    GLint ok = 0;
    glGetProgramiv(program, GL_LINK_STATUS, &ok);
    if (!ok) {
        std::string log(4096, '\0');
        GLsizei length = 0;
        glGetProgramInfoLog(program, static_cast<GLsizei>(log.size()), &length, log.data());
        log.resize(static_cast<std::size_t>(length));
        glDeleteProgram(program);
        return Status(ErrorCode::Internal, "shader link failed: " + log);
    }
    return program;
}

} // namespace ff::runtime
