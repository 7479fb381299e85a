#include "Hud.h"

#include <ff/runtime/GlProgram.h>
#include <ff/runtime/Units.h>

#include <glad/gl.h>

#include <stb_easy_font.h>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>

namespace ff::viewer {

namespace {

// stb_easy_font's vertex: position in pixels (y down), z unused, RGBA8 colour.
struct FontVertex {
    float x, y, z;
    std::uint8_t color[4];
};
static_assert(sizeof(FontVertex) == 16);

constexpr std::size_t kMaxTextBytes = 1024;
constexpr std::size_t kBytesPerChar = 300; // stb_easy_font: "~270 bytes per character"
constexpr float kMargin = 6.0f;            // font pixels around the text

const char* const kVertexShader = R"(#version 450 core
layout(location = 0) in vec2 aPosition; // font pixels, origin top left, y down
layout(location = 1) in vec4 aColor;
uniform vec2 uPixelToClip;               // scale / framebuffer size * 2
out vec4 vColor;
void main() {
    gl_Position = vec4(aPosition.x * uPixelToClip.x - 1.0, 1.0 - aPosition.y * uPixelToClip.y, 0.0, 1.0);
    vColor = aColor;
}
)";

const char* const kFragmentShader = R"(#version 450 core
in vec4 vColor;
layout(location = 0) out vec4 fragColor;
void main() { fragColor = vColor; }
)";

// Appends rather than inserting: GCC 12 reports a false -Wrestrict (its bug 105329) for
// std::string::insert once inlined in a Release build.
std::string withThousands(std::uint64_t value) {
    const std::string digits = std::to_string(value);
    std::string out;
    out.reserve(digits.size() + digits.size() / 3);
    for (std::size_t i = 0; i < digits.size(); ++i) {
        if (i > 0 && (digits.size() - i) % 3 == 0)
            out += ',';
        out += digits[i];
    }
    return out;
}

} // namespace

std::string formatHud(const HudInfo& info) {
    char line[256];
    std::string text;
    const double fps = info.frameMs > 0.0 ? 1000.0 / info.frameMs : 0.0;
    std::snprintf(
            line,
            sizeof(line),
            "%.1f fps  %.1f ms/frame (select %.1f, draw %.1f)  %dx%d\n",
            fps,
            info.frameMs,
            info.selectMs,
            info.drawMs,
            info.width,
            info.height);
    text += line;
    std::snprintf(
            line,
            sizeof(line),
            "eps %g px  method %s  nav %s\n",
            static_cast<double>(info.epsilonPixels),
            runtime::methodName(info.method),
            info.navigation);
    text += line;
    text += "triangles " + withThousands(info.trianglesDrawn) + "  cubes " +
            withThousands(info.cubesDrawn) + "  deferred " + withThousands(info.debt) + "\n";
    if (info.occlusion) {
        std::snprintf(
                line,
                sizeof(line),
                "occlusion %.1f ms  queries %llu (waited %llu)  occluded %llu (%s triangles)  render rate %.2f %%%s\n",
                info.occlusionMs,
                static_cast<unsigned long long>(info.occlusionQueries),
                static_cast<unsigned long long>(info.queriesWaited),
                static_cast<unsigned long long>(info.nodesOccluded),
                withThousands(info.trianglesOccluded).c_str(),
                info.renderRatePercent,
                info.occlusionSkipped ? "  (untested: culling did not pay)" : "");
        text += line;
    }
    std::snprintf(
            line,
            sizeof(line),
            "resident %.1f MB  %s budget %s  requests %llu\n",
            static_cast<double>(info.residentBytes) / 1e6,
            info.budgetName,
            runtime::formatBytes(info.budgetBytes).c_str(),
            static_cast<unsigned long long>(info.requestsInFlight));
    text += line;
    text += "[ ] eps  M method  - = budget  Tab orbit/fly  R reset  P shot  H hud  Esc quit";
    return text;
}

Result<std::unique_ptr<Hud>> Hud::create() {
    std::unique_ptr<Hud> hud(new Hud());
    Result<std::uint32_t> program = runtime::linkGlProgram({kVertexShader}, kFragmentShader);
    if (!program)
        return program.status().withContext("HUD");
    hud->mProgram = *program;

    GLuint buffers[2];
    glGenBuffers(2, buffers);
    hud->mVertices = buffers[0];
    hud->mIndices = buffers[1];
    glGenVertexArrays(1, &hud->mVao);
    glBindVertexArray(hud->mVao);
    glBindVertexBuffer(0, hud->mVertices, 0, sizeof(FontVertex));
    glVertexAttribFormat(0, 2, GL_FLOAT, GL_FALSE, offsetof(FontVertex, x));
    glVertexAttribFormat(1, 4, GL_UNSIGNED_BYTE, GL_TRUE, offsetof(FontVertex, color));
    for (GLuint a = 0; a < 2; ++a) {
        glVertexAttribBinding(a, 0);
        glEnableVertexAttribArray(a);
    }
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, hud->mIndices); // recorded in the VAO
    glBindVertexArray(0);
    hud->mScratch.resize(kMaxTextBytes * kBytesPerChar);
    if (const GLenum error = glGetError(); error != GL_NO_ERROR)
        return Status(
                ErrorCode::Internal,
                "OpenGL error " + std::to_string(error) + " while creating the HUD");
    return hud;
}

Hud::~Hud() {
    const GLuint buffers[] = {mVertices, mIndices};
    glDeleteBuffers(2, buffers);
    glDeleteVertexArrays(1, &mVao);
    glDeleteProgram(mProgram);
}

void Hud::draw(const std::string& text, glm::ivec2 framebufferSize) {
    if (framebufferSize.x <= 0 || framebufferSize.y <= 0 || text.empty())
        return;
    mText.assign(text, 0, kMaxTextBytes);
    // Quad 0 is the panel behind the text; stb_easy_font's quads follow it.
    auto* vertices = reinterpret_cast<FontVertex*>(mScratch.data());
    const int textQuads = stb_easy_font_print(
            kMargin,
            kMargin,
            mText.data(),
            nullptr,
            vertices + 4,
            static_cast<int>(mScratch.size() - 4 * sizeof(FontVertex)));
    const auto width = static_cast<float>(stb_easy_font_width(mText.data())) + 2.0f * kMargin;
    const auto height = static_cast<float>(stb_easy_font_height(mText.data())) + 2.0f * kMargin;
    const FontVertex panel[4] = {
            {0, 0, 0, {0, 0, 0, 150}},
            {width, 0, 0, {0, 0, 0, 150}},
            {width, height, 0, {0, 0, 0, 150}},
            {0, height, 0, {0, 0, 0, 150}}};
    std::memcpy(vertices, panel, sizeof(panel));
    const auto quads = static_cast<std::size_t>(textQuads) + 1;

    glBindVertexArray(mVao);
    const std::size_t vertexBytes = quads * 4 * sizeof(FontVertex);
    glBindBuffer(GL_ARRAY_BUFFER, mVertices);
    if (vertexBytes > mVertexCapacity) {
        mVertexCapacity = std::max(vertexBytes, 2 * mVertexCapacity);
        glBufferData(
                GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(mVertexCapacity), nullptr, GL_STREAM_DRAW);
    }
    glBufferSubData(GL_ARRAY_BUFFER, 0, static_cast<GLsizeiptr>(vertexBytes), vertices);
    if (quads > mIndexQuads) { // two triangles per quad, shared by every frame
        mIndexQuads = std::max(quads, 2 * mIndexQuads);
        std::vector<GLuint> indices(mIndexQuads * 6);
        for (std::size_t q = 0; q < mIndexQuads; ++q) {
            const auto v = static_cast<GLuint>(4 * q);
            const GLuint quad[6] = {v, v + 1, v + 2, v, v + 2, v + 3};
            std::copy(quad, quad + 6, indices.begin() + static_cast<std::ptrdiff_t>(6 * q));
        }
        glBufferData(
                GL_ELEMENT_ARRAY_BUFFER,
                static_cast<GLsizeiptr>(indices.size() * sizeof(GLuint)),
                indices.data(),
                GL_STATIC_DRAW);
    }

    // Larger windows get larger letters (stb_easy_font's glyphs are ~7 pixels tall).
    const float scale = std::max(1.0f, std::floor(static_cast<float>(framebufferSize.y) / 500.0f));
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glViewport(0, 0, framebufferSize.x, framebufferSize.y);
    glDisable(GL_FRAMEBUFFER_SRGB);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_CULL_FACE);
    glEnable(GL_BLEND);
    glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
    glUseProgram(mProgram);
    glUniform2f(
            glGetUniformLocation(mProgram, "uPixelToClip"),
            2.0f * scale / static_cast<float>(framebufferSize.x),
            2.0f * scale / static_cast<float>(framebufferSize.y));
    glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(quads * 6), GL_UNSIGNED_INT, nullptr);
    glDisable(GL_BLEND);
    glBindVertexArray(0);
}

} // namespace ff::viewer
