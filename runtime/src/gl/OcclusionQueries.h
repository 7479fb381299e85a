#pragma once

#include "GlHeaders.h"

#include <ff/runtime/Traversal.h>
#include <ff/storage/Status.h>

#include <glm/glm.hpp>

#include <memory>
#include <span>
#include <vector>

namespace ff::runtime::gl {

/**
 * Hardware occlusion queries (GL_ANY_SAMPLES_PASSED_CONSERVATIVE, GL 4.3) over boxes given by
 * their world-space corners, drawn into whatever framebuffer is bound with colour and depth
 * writes off and the depth test at <=, so a box face lying on a drawn surface counts as
 * visible. Query objects are pooled and reused frame after frame. Needs a current GL context.
 */
class OcclusionQueries {
public:
    [[nodiscard]] static Result<std::unique_ptr<OcclusionQueries>> create();
    ~OcclusionQueries();
    OcclusionQueries(const OcclusionQueries&) = delete;
    OcclusionQueries& operator=(const OcclusionQueries&) = delete;

    /** Starts a frame drawn with `viewProjection`: every ticket of the last frame is void. */
    void beginFrame(const glm::mat4& viewProjection);
    [[nodiscard]] QueryTicket issue(std::span<const OcclusionBox> group);
    [[nodiscard]] bool ready(QueryTicket ticket) const;
    [[nodiscard]] bool anyVisible(QueryTicket ticket) const;
    /** Issues one query and waits for it, so its program is compiled before the first frame
     *  (llvmpipe compiles at the first draw). Its ticket is void at the next beginFrame(). */
    void warm();

    /** Boxes one query draws at most (a larger group is split over several draws). */
    static constexpr std::size_t kBoxesPerDraw = 8;

private:
    OcclusionQueries() = default;

    GLenum mTarget = GL_ANY_SAMPLES_PASSED_CONSERVATIVE;
    GLuint mProgram = 0;
    GLuint mVao = 0;
    GLint mCornersLocation = -1;
    GLint mViewProjectionLocation = -1;
    std::vector<GLuint> mPool; ///< query objects; [0, mUsed) belong to this frame
    std::size_t mUsed = 0;
    glm::mat4 mViewProjection{1.0f};
    std::vector<glm::vec3> mCorners; ///< the uniform array of one draw
};

} // namespace ff::runtime::gl
