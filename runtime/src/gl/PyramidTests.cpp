#include "PyramidTests.h"

#include <algorithm>

namespace ff::runtime::gl {

void PyramidTests::beginFrame(
        const glm::mat4& viewProjection, GLuint framebuffer, int width, int height) {
    mViewProjection = viewProjection;
    mFramebuffer = framebuffer;
    mWidth = width;
    mHeight = height;
    mDepthChanged = true;
    mAnswers.clear();
    mPendingBoxes.clear();
    mPendingTickets.clear();
}

QueryTicket PyramidTests::issue(std::span<const OcclusionBox> group) {
    const auto ticket = static_cast<QueryTicket>(mAnswers.size());
    mAnswers.push_back(-1);
    mPendingBoxes.insert(mPendingBoxes.end(), group.begin(), group.end());
    mPendingTickets.emplace_back(ticket, static_cast<std::uint32_t>(group.size()));
    return ticket;
}

bool PyramidTests::ready(QueryTicket ticket) const {
    return ticket >= mAnswers.size() || mAnswers[ticket] >= 0;
}

bool PyramidTests::anyVisible(QueryTicket ticket) {
    if (ticket >= mAnswers.size())
        return true; // not this frame's: Unknown is visible
    if (mAnswers[ticket] < 0)
        answerPending();
    return mAnswers[ticket] != 0;
}

void PyramidTests::answerPending() {
    if (mPendingTickets.empty())
        return;
    if (mDepthChanged) { // one readback answers every test issued since the last
        mDepth.resize(static_cast<std::size_t>(mWidth) * static_cast<std::size_t>(mHeight));
        glBindFramebuffer(GL_READ_FRAMEBUFFER, mFramebuffer);
        glPixelStorei(GL_PACK_ALIGNMENT, 4);
        glReadPixels(0, 0, mWidth, mHeight, GL_DEPTH_COMPONENT, GL_FLOAT, mDepth.data());
        mPyramid.build(mWidth, mHeight, mDepth);
        mDepthChanged = false;
    }
    std::size_t box = 0;
    for (const auto& [ticket, count] : mPendingTickets) {
        const auto group = std::span(mPendingBoxes).subspan(box, count);
        box += count;
        const bool visible = std::any_of(group.begin(), group.end(), [&](const OcclusionBox& b) {
            return boxMayBeVisible(mPyramid, b, mViewProjection, mWidth, mHeight);
        });
        mAnswers[ticket] = visible ? 1 : 0;
    }
    mPendingBoxes.clear();
    mPendingTickets.clear();
}

} // namespace ff::runtime::gl
