#pragma once

#include "../DepthPyramid.h"
#include "GlHeaders.h"

#include <ff/runtime/Traversal.h>

#include <glm/glm.hpp>

#include <cstdint>
#include <span>
#include <utility>
#include <vector>

namespace ff::runtime::gl {

/**
 * `--occlusion-backend hzb`: occlusion tests answered on the CPU against a max-depth pyramid of
 * the depth read back from `framebuffer` (docs/methods.md §9). Tests are answered lazily, at the
 * next submit() or wait, all of them against one readback made only if depth was drawn since the
 * last: against the depth then, which only came nearer, so what it hides stays hidden in the
 * finished frame. Needs a current GL context.
 */
class PyramidTests {
public:
    /** Starts a frame drawn with `viewProjection` into the width x height `framebuffer`. */
    void beginFrame(const glm::mat4& viewProjection, GLuint framebuffer, int width, int height);
    /** Geometry was drawn: the next answers need a fresh readback. */
    void depthDrawn() noexcept { mDepthChanged = true; }

    [[nodiscard]] QueryTicket issue(std::span<const OcclusionBox> group);
    void submit() { answerPending(); }
    [[nodiscard]] bool ready(QueryTicket ticket) const;
    [[nodiscard]] bool anyVisible(QueryTicket ticket);

private:
    void answerPending();

    glm::mat4 mViewProjection{1.0f};
    GLuint mFramebuffer = 0;
    int mWidth = 0;
    int mHeight = 0;
    bool mDepthChanged = true;
    std::vector<float> mDepth;
    DepthPyramid mPyramid;
    std::vector<std::int8_t> mAnswers; ///< per ticket of this frame: -1 until answered
    std::vector<OcclusionBox> mPendingBoxes;
    std::vector<std::pair<QueryTicket, std::uint32_t>> mPendingTickets; ///< ticket, its box count
};

} // namespace ff::runtime::gl
