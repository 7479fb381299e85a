#include "OcclusionQueries.h"

#include <ff/runtime/GlProgram.h>

#include <glm/gtc/type_ptr.hpp>

#include <algorithm>
#include <string>

namespace ff::runtime::gl {

namespace {

// Up to kBoxesPerDraw boxes of 36 vertices (12 triangles) each, from eight corners a box; corner
// i has bit 0 = x max, bit 1 = y max, bit 2 = z max, as OcclusionBox says. Every triangle is
// counter-clockwise seen from outside the box.
constexpr const char* kBoxVertexShader = R"(#version 450 core
uniform mat4 uViewProjection;
uniform vec3 uCorners[64];
const int kCorner[36] = int[36](
    0, 2, 3, 0, 3, 1,  4, 5, 7, 4, 7, 6,  0, 1, 5, 0, 5, 4,
    2, 6, 7, 2, 7, 3,  0, 4, 6, 0, 6, 2,  1, 3, 7, 1, 7, 5);
void main() {
    int box = gl_VertexID / 36;
    gl_Position = uViewProjection * vec4(uCorners[8 * box + kCorner[gl_VertexID % 36]], 1.0);
}
)";

constexpr const char* kBoxFragmentShader = R"(#version 450 core
void main() {}
)";

} // namespace

Result<std::unique_ptr<OcclusionQueries>> OcclusionQueries::create() {
    std::unique_ptr<OcclusionQueries> queries(new OcclusionQueries());
    FF_ASSIGN_OR_RETURN(queries->mProgram, linkGlProgram({kBoxVertexShader}, kBoxFragmentShader));
    queries->mCornersLocation = glGetUniformLocation(queries->mProgram, "uCorners");
    queries->mViewProjectionLocation = glGetUniformLocation(queries->mProgram, "uViewProjection");
    glGenVertexArrays(1, &queries->mVao); // attribute-less, but core GL draws need one bound
    queries->mCorners.reserve(8 * kBoxesPerDraw);
    // The conservative target is core since GL 4.3; a context that refuses it gets the exact one.
    while (glGetError() != GL_NO_ERROR) {
    }
    GLuint probe = 0;
    glGenQueries(1, &probe);
    glBeginQuery(GL_ANY_SAMPLES_PASSED_CONSERVATIVE, probe);
    if (glGetError() == GL_NO_ERROR)
        glEndQuery(GL_ANY_SAMPLES_PASSED_CONSERVATIVE);
    else
        queries->mTarget = GL_ANY_SAMPLES_PASSED;
    glDeleteQueries(1, &probe);
    if (const GLenum error = glGetError(); error != GL_NO_ERROR)
        return Status(
                ErrorCode::Internal,
                "OpenGL error " + std::to_string(error) + " setting up occlusion queries");
    return queries;
}

OcclusionQueries::~OcclusionQueries() {
    if (!mPool.empty())
        glDeleteQueries(static_cast<GLsizei>(mPool.size()), mPool.data());
    glDeleteVertexArrays(1, &mVao);
    glDeleteProgram(mProgram);
}

void OcclusionQueries::beginFrame(const glm::mat4& viewProjection) {
    mUsed = 0;
    mViewProjection = viewProjection;
}

QueryTicket OcclusionQueries::issue(std::span<const OcclusionBox> group) {
    if (mUsed == mPool.size()) {
        const std::size_t grown = std::max<std::size_t>(64, mPool.size() * 2);
        mPool.resize(grown, 0);
        glGenQueries(static_cast<GLsizei>(grown - mUsed), mPool.data() + mUsed);
    }
    const auto ticket = static_cast<QueryTicket>(mUsed++);
    glUseProgram(mProgram);
    glUniformMatrix4fv(mViewProjectionLocation, 1, GL_FALSE, glm::value_ptr(mViewProjection));
    glBindVertexArray(mVao);
    glColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
    glDepthMask(GL_FALSE);
    glDepthFunc(GL_LEQUAL);
    glEnable(GL_CULL_FACE); // a box not holding the eye shows its silhouette with front faces
    glCullFace(GL_BACK);
    glFrontFace(GL_CCW);
    glBeginQuery(mTarget, mPool[ticket]);
    for (std::size_t first = 0; first < group.size(); first += kBoxesPerDraw) {
        const std::size_t count = std::min(kBoxesPerDraw, group.size() - first);
        mCorners.clear();
        for (std::size_t b = first; b < first + count; ++b)
            mCorners.insert(mCorners.end(), group[b].corners.begin(), group[b].corners.end());
        glUniform3fv(
                mCornersLocation,
                static_cast<GLsizei>(mCorners.size()),
                glm::value_ptr(mCorners[0]));
        glDrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(36 * count));
    }
    glEndQuery(mTarget);
    glDisable(GL_CULL_FACE);
    glDepthFunc(GL_LESS);
    glDepthMask(GL_TRUE);
    glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    return ticket;
}

void OcclusionQueries::warm() {
    beginFrame(glm::mat4(1.0f));
    OcclusionBox box;
    for (std::size_t c = 0; c < box.corners.size(); ++c)
        box.corners[c] = glm::vec3(c & 1 ? 0.5f : -0.5f, c & 2 ? 0.5f : -0.5f, c & 4 ? 0.5f : -0.5f);
    const QueryTicket ticket = issue({&box, 1});
    (void)anyVisible(ticket);
}

bool OcclusionQueries::ready(QueryTicket ticket) const {
    GLuint available = 0;
    glGetQueryObjectuiv(mPool[ticket], GL_QUERY_RESULT_AVAILABLE, &available);
    return available != 0;
}

bool OcclusionQueries::anyVisible(QueryTicket ticket) const {
    GLuint passed = 0;
    glGetQueryObjectuiv(mPool[ticket], GL_QUERY_RESULT, &passed);
    return passed != 0;
}

} // namespace ff::runtime::gl
