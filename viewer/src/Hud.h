#pragma once

#include "ViewerControls.h"

#include <ff/storage/Status.h>

#include <glm/glm.hpp>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace ff::viewer {

/** The HUD's text for `info`: a few lines separated by '\n'. */
std::string formatHud(const HudInfo& info);

/**
 * Text over the window's top-left corner on a translucent panel, drawn with stb_easy_font's
 * quads by a tiny GL 4.5 core program built through the runtime's GL layer (no legacy GL).
 * Draws into framebuffer 0 after StreamingSession::present(); needs the window's context
 * current. Main thread only.
 */
class Hud {
public:
    [[nodiscard]] static Result<std::unique_ptr<Hud>> create();
    ~Hud();
    Hud(const Hud&) = delete;
    Hud& operator=(const Hud&) = delete;

    /** Draws `text` at the top left of a framebuffer `framebufferSize` pixels large. Leaves
     *  blending and depth testing off. */
    void draw(const std::string& text, glm::ivec2 framebufferSize);

private:
    Hud() = default;

    unsigned mProgram = 0;
    unsigned mVao = 0;
    unsigned mVertices = 0;
    unsigned mIndices = 0;
    std::size_t mVertexCapacity = 0; ///< bytes
    std::size_t mIndexQuads = 0;     ///< quads the index buffer covers
    std::vector<char> mScratch;      ///< stb_easy_font's output
    std::string mText;               ///< stb_easy_font wants a mutable string
};

} // namespace ff::viewer
