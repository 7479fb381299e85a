#include <ff/runtime/Renderer.h>

#include "../CachedClusterPage.h"
#include "GlHeaders.h"
#include "OcclusionQueries.h"
#include "PyramidTests.h"
#include "Shaders.h"

#include <ff/runtime/GlProgram.h>

#include <ff/cache/PageLru.h>
#include <ff/storage/ShadingModel.h>

#include <glm/gtc/type_ptr.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <initializer_list>
#include <optional>
#include <cstddef>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <vector>

namespace ff::runtime {

namespace {

struct IndirectCommand {
    GLuint count;
    GLuint instanceCount;
    GLuint first;
    GLuint baseInstance;
};

/** A cluster's draw (format 2): u8 indices from byte `firstIndex` of the arena. */
struct IndexedCommand {
    GLuint count;
    GLuint instanceCount;
    GLuint firstIndex;
    GLint baseVertex;
    GLuint baseInstance;
};

// Bind-to-edit rather than direct state access: OSMesa exports the GL 4.3 entry points but
// not the 4.5 DSA ones, and farfield links GL functions directly (no loader).
void bufferData(GLuint buffer, GLsizeiptr bytes, const void* data, GLenum usage) {
    glBindBuffer(GL_COPY_WRITE_BUFFER, buffer);
    glBufferData(GL_COPY_WRITE_BUFFER, bytes, data, usage);
}

void bufferSubData(GLuint buffer, GLintptr offset, GLsizeiptr bytes, const void* data) {
    glBindBuffer(GL_COPY_WRITE_BUFFER, buffer);
    glBufferSubData(GL_COPY_WRITE_BUFFER, offset, bytes, data);
}

/** The bound vertex array's attributes 0-2: PackedVertex (20 bytes) from binding 0. */
void formatPackedVertices() {
    glVertexAttribFormat(0, 3, GL_FLOAT, GL_FALSE, offsetof(storage::PackedVertex, position));
    // As integers: the shader tells the unlit code (-32768, -32768) apart from -32767, which a
    // normalized attribute maps to the same -1.
    glVertexAttribIFormat(1, 2, GL_SHORT, offsetof(storage::PackedVertex, normalOct));
    glVertexAttribFormat(2, 4, GL_UNSIGNED_BYTE, GL_TRUE, offsetof(storage::PackedVertex, color));
    for (GLuint a = 0; a < 3; ++a) {
        glVertexAttribBinding(a, 0);
        glEnableVertexAttribArray(a);
    }
}

// Grows a buffer to at least `bytes` (contents are rewritten every frame, so none are kept).
void ensureCapacity(GLuint buffer, GLsizeiptr& capacity, GLsizeiptr bytes) {
    if (bytes <= capacity)
        return;
    capacity = std::max<GLsizeiptr>(bytes, capacity * 2);
    bufferData(buffer, capacity, nullptr, GL_DYNAMIC_DRAW);
}

double millisecondsSince(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

/** The occluder shader's opacity sum is -log2(transmittance) in these steps. */
constexpr double kOpacityUnit = 65536.0;
/** The sum of a face of alpha 1 (the threshold at δ = 0): more than 255 faces of alpha 254/255. */
constexpr GLuint kOpaqueSum = 1u << 24;
/** An occluder's depth lies this far (4 steps of the 24-bit depth buffer) behind its face. */
constexpr float kOccluderDepthBias = 4.0f / 16777216.0f;

/** The sum at which a sample's transmittance has fallen to `threshold` (0: only opaque faces). */
GLuint occludingOpacity(float threshold) {
    if (!(threshold > 0.0f))
        return kOpaqueSum;
    const double sum = std::ceil(-std::log2(static_cast<double>(std::min(threshold, 1.0f))) * kOpacityUnit);
    return static_cast<GLuint>(std::clamp(sum, 1.0, static_cast<double>(kOpaqueSum)));
}

} // namespace

struct Renderer::Impl {
    RendererOptions options;
    GLuint geometryProgram = 0;
    GLuint roundSplatProgram = 0; ///< point clusters as discs (square ones: geometryProgram)
    GLuint cubeProgram = 0;
    GLuint cubePointProgram = 0;
    GLuint cubeOccluderProgram = 0;      ///< cubes as occluders (OcclusionOptions::cubesOcclude)
    GLuint cubePointOccluderProgram = 0; ///< the same for cubes drawn as points
    /** The oracle's (visibleParts): made by its first call, as only benchmarks ask. */
    GLuint visibleTriangleProgram = 0, visibleCubeProgram = 0, visibleCubePointProgram = 0;
    GLuint visibleBits = 0; ///< their storage buffer: a bit per triangle, then per cube
    GLsizeiptr visibleBitsCap = 0;
    GLuint geometryVao = 0;
    GLuint cubeVao = 0;
    // The page arena: one slot per resident geometry page. Format 1: the page's triangle slots.
    // Format 2 (clustered): the decoded page's vertices, then its u8 cluster-local indices, the
    // same buffer bound as the element array; decoded off this thread (`decodedGeometry`) a frame
    // before the upload, or, for a page the arena evicted within the frame that admitted it,
    // here from the cached bytes the draw carries (`grids`, FrameStats::pagesDecodedOnDraw).
    bool clustered = false;
    IDecodedGeometry* decodedGeometry = nullptr;
    bool decodeOnDraw = false; ///< setDecodeOnDraw(): admit pages not decoded yet, decode them here
    std::vector<storage::PositionGrid> grids;
    std::uint64_t maxDecodedBytes = 0;
    GLuint arena = 0;
    GLsizeiptr slotBytes = 0;
    GLuint verticesPerSlot = 0;
    std::uint32_t slotCount = 0; ///< slots the arena holds now
    std::uint32_t maxSlots = 0;  ///< slots the GPU budget allows
    std::unordered_map<std::uint64_t, std::uint32_t> slotOfPage;
    std::vector<std::uint64_t> pageOfSlot;
    std::vector<std::uint32_t> slotBatch; ///< batch number that last used a slot
    std::vector<std::uint32_t> freeSlots;
    cache::PageLru lru;
    std::uint32_t batch = 0;
    // The frame in progress.
    FrameOutput output = FrameOutput::Image;
    int frameWidth = 0, frameHeight = 0, frameSupersample = 1;
    glm::mat4 frameViewProjection{1.0f};
    float framePixelScale = 1.0f;
    GLuint frameOccludes = 0; ///< the opacity sum at which a sample occludes (cube occluders)
    std::uint32_t uploadLimit = 0;              ///< FrameBudgets::gpuUploadsPerFrame
    std::unordered_set<std::uint64_t> admitted; ///< pages not in the arena admitted this frame
    // Per-batch buffers, a ring of them: rewriting a buffer the GPU may still be reading (the
    // batch before, when an occlusion query flushed it) would wait for that batch to finish.
    // The cube buffer of each set goes round on its own (cubeSlot).
    struct BatchBuffers {
        GLuint transforms = 0, normalMatrices = 0, localEyes = 0, indirect = 0, cubes = 0, pointDraws = 0;
        GLsizeiptr transformsCap = 0, normalsCap = 0, eyesCap = 0, indirectCap = 0, cubesCap = 0, pointDrawsCap = 0;
    };
    static constexpr std::size_t kBatchBufferSets = 4;
    std::array<BatchBuffers, kBatchBufferSets> ring;
    std::size_t ringSlot = 0;
    BatchBuffers& current() { return ring[ringSlot]; }
    /** The cube buffers go round on their own, one step per batch that draws cubes: stepped
     *  with every batch, a frame that also draws a batch without cubes (occlusion culling's
     *  geometry pass) put its large cube batch in a slot not grown yet frame after frame, and
     *  each growth cost a frame 40-80 ms (the forest's corner view, the three frames after the
     *  cold one). */
    std::size_t cubeSlot = 0;
    GLuint iota = 0;
    GLsizeiptr iotaCap = 0;
    std::vector<IndirectCommand> commands;
    std::vector<IndexedCommand> indexedCommands;
    std::vector<IndirectCommand> pointCommands; ///< format 2's point clusters (splats)
    /** Per point command (its baseInstance): the transform and the diameter in pixels, read by
     *  pointVao's per-instance attributes. */
    struct PointDraw {
        GLuint transform;
        float pixels;
    };
    std::vector<PointDraw> pointDraws;
    GLuint pointVao = 0;  ///< geometryVao's vertices, with PointDraw per draw
    SplatStyle splats;    ///< how the batch draws them
    std::vector<glm::mat4> normalScratch;
    std::vector<glm::vec4> eyeScratch;
    // Render target.
    GLuint framebuffer = 0, colorTexture = 0, depthBuffer = 0;
    /** Opacity composited over each sample by occluder cubes and the farthest depth in it, two
     *  layers (kCubeOccluderFragmentShader); made by the first frame with cube occluders,
     *  dropped with the target. */
    GLuint opacityTexture = 0;
    int targetWidth = 0, targetHeight = 0;
    std::vector<std::uint8_t> readback;
    // present(): an RGBA8 view of colorTexture to blit from; made on demand, dropped with the target.
    GLuint presentFramebuffer = 0, presentView = 0;
    std::unique_ptr<gl::OcclusionQueries> queries;
    gl::PyramidTests pyramidTests; ///< --occlusion-backend hzb
    OcclusionBackend occlusionBackend = OcclusionBackend::Queries; ///< this frame's

    ~Impl();
    Status ensureTarget(int width, int height);
    /** The opacity layers of cube occluders, at the target's size (made once per target). */
    void ensureOpacityTexture();
    /** Draws each program once with the state a frame draws it with (warmPrograms()). */
    Status warmPrograms();
    Status ensurePresentSource();
    void uploadTransforms(const DrawList& list);
    Result<std::uint32_t> residentSlot(const GeometryDraw& draw, FrameStats& stats);
    void growArena();
    /** Binds the arena as the geometry's vertex (and, clustered, element) buffer. */
    void bindArena();
    /** The indexed commands drawing `draw`'s clusters from `slot` (false: a page that does not
     *  view as a cached cluster page, or clusters past its table, which NodePages already
     *  refused to hand out). */
    bool appendClusterCommands(const GeometryDraw& draw, std::uint32_t slot);
    /** Binds `program` (geometryProgram or roundSplatProgram) with the frame's uniforms. */
    void useGeometryProgram(GLuint program, const glm::mat4& viewProjection);
    void drawBatch(const glm::mat4& viewProjection);
    Status drawGeometry(const DrawList& list, const glm::mat4& viewProjection, FrameStats& stats);
    void drawCubes(const DrawList& list, const glm::mat4& viewProjection, float pixelScale);
    /** Uploads the list's cubes and binds them, `program` and its view-projection for drawing. */
    void bindCubes(const DrawList& list, GLuint program, const glm::mat4& viewProjection);
    /** Draws the bound cubes: an 18-vertex instance each, or a sized point each. */
    void drawBoundCubes(const DrawList& list, GLuint program, float pixelScale);
};

Renderer::Impl::~Impl() {
    const GLuint buffers[] = {arena, iota};
    glDeleteBuffers(2, buffers);
    for (const BatchBuffers& set : ring) {
        const GLuint perBatch[] = {set.transforms, set.normalMatrices, set.localEyes, set.indirect, set.cubes, set.pointDraws};
        glDeleteBuffers(6, perBatch);
    }
    const GLuint vaos[] = {geometryVao, cubeVao, pointVao};
    glDeleteVertexArrays(3, vaos);
    glDeleteProgram(geometryProgram);
    glDeleteProgram(roundSplatProgram);
    glDeleteProgram(cubeProgram);
    glDeleteProgram(cubePointProgram);
    glDeleteProgram(cubeOccluderProgram);
    glDeleteProgram(cubePointOccluderProgram);
    glDeleteProgram(visibleTriangleProgram);
    glDeleteProgram(visibleCubeProgram);
    glDeleteProgram(visibleCubePointProgram);
    glDeleteBuffers(1, &visibleBits);
    glDeleteFramebuffers(1, &framebuffer);
    glDeleteTextures(1, &colorTexture);
    glDeleteTextures(1, &opacityTexture);
    glDeleteRenderbuffers(1, &depthBuffer);
    glDeleteFramebuffers(1, &presentFramebuffer);
    glDeleteTextures(1, &presentView);
}

Renderer::Renderer(std::unique_ptr<Impl> impl) : mImpl(std::move(impl)) {}
Renderer::~Renderer() = default;


Result<std::unique_ptr<Renderer>> Renderer::create(
        const storage::SceneIndex& scene, const RendererOptions& options, IDecodedGeometry* decodedGeometry) {
    const bool clustered = scene.formatVersion() == storage::kFormatVersion2;
    if (clustered && decodedGeometry == nullptr)
        return Status(ErrorCode::InvalidArgument, "a format 2 scene is drawn through a decode stage");
    auto impl = std::make_unique<Impl>();
    impl->options = options;
    FF_ASSIGN_OR_RETURN(impl->geometryProgram, linkGlProgram({gl::kGeometryVertexShader}, gl::kGeometryFragmentShader));
    FF_ASSIGN_OR_RETURN(impl->roundSplatProgram,
                        linkGlProgram({gl::kGeometryVertexShader}, gl::kRoundSplatFragmentShader));
    FF_ASSIGN_OR_RETURN(impl->cubeProgram, linkGlProgram({gl::kCubeShaderInputs, gl::kCubeVertexShader}, gl::kCubeFragmentShader));
    FF_ASSIGN_OR_RETURN(impl->queries, gl::OcclusionQueries::create());
    FF_ASSIGN_OR_RETURN(impl->cubePointProgram, linkGlProgram({gl::kCubeShaderInputs, gl::kCubePointVertexShader}, gl::kCubeFragmentShader));
    FF_ASSIGN_OR_RETURN(impl->cubeOccluderProgram,
                        linkGlProgram({gl::kCubeShaderInputs, gl::kCubeVertexShader}, gl::kCubeOccluderFragmentShader));
    FF_ASSIGN_OR_RETURN(impl->cubePointOccluderProgram, linkGlProgram({gl::kCubeShaderInputs, gl::kCubePointVertexShader},
                                                                      gl::kCubeOccluderFragmentShader));

    // Slots hold a page's triangles without its trailer, so vertex offsets stay whole vertices;
    // a decoded cluster page's vertices and indices, rounded up to whole vertices.
    impl->clustered = clustered;
    if (impl->clustered) {
        impl->decodedGeometry = decodedGeometry;
        for (const storage::PrototypeV2& p : scene.prototypesV2())
            impl->grids.push_back(p.grid);
        impl->maxDecodedBytes = storage::maxDecodedClusterBytes(scene.pageSize());
        constexpr std::uint64_t vertex = sizeof(storage::PackedVertex);
        const std::uint64_t decoded = storage::maxDecodedClusterBytes(scene.pageSize());
        impl->slotBytes = static_cast<GLsizeiptr>((decoded + vertex - 1) / vertex * vertex);
        impl->verticesPerSlot = static_cast<GLuint>(static_cast<std::uint64_t>(impl->slotBytes) / vertex);
    } else {
        const std::uint32_t trianglesPerPage = storage::trianglesPerPage(scene.pageSize());
        impl->slotBytes = static_cast<GLsizeiptr>(trianglesPerPage * sizeof(storage::PackedTriangle));
        impl->verticesPerSlot = trianglesPerPage * 3;
    }
    // The arena starts small and doubles up to the budget: on llvmpipe GPU buffers are system
    // memory, and a budget is a ceiling, not an amount to take up front. Clustered draws address
    // the arena's bytes with 32-bit index offsets: it stays below 2 GiB.
    const std::uint64_t arenaBytes =
            impl->clustered ? std::min<std::uint64_t>(options.gpuBudgetBytes, 1ull << 31) : options.gpuBudgetBytes;
    impl->maxSlots = static_cast<std::uint32_t>(
            std::clamp<std::uint64_t>(arenaBytes / static_cast<std::uint64_t>(impl->slotBytes), 1, 1u << 20));
    impl->slotCount = std::min<std::uint32_t>(impl->maxSlots, 64);
    impl->pageOfSlot.assign(impl->slotCount, 0);
    impl->slotBatch.assign(impl->slotCount, 0);
    for (std::uint32_t s = impl->slotCount; s-- > 0;)
        impl->freeSlots.push_back(s);

    GLuint buffers[2];
    glGenBuffers(2, buffers);
    impl->arena = buffers[0];
    impl->iota = buffers[1];
    for (Impl::BatchBuffers& set : impl->ring) {
        GLuint perBatch[6];
        glGenBuffers(6, perBatch);
        set.transforms = perBatch[0];
        set.normalMatrices = perBatch[1];
        set.localEyes = perBatch[2];
        set.indirect = perBatch[3];
        set.cubes = perBatch[4];
        set.pointDraws = perBatch[5];
    }
    bufferData(impl->arena, impl->slotBytes * impl->slotCount, nullptr, GL_DYNAMIC_DRAW);

    // Geometry: PackedVertex layout (20 bytes) straight from the pages.
    glGenVertexArrays(1, &impl->geometryVao);
    impl->bindArena();
    glBindVertexArray(impl->geometryVao);
    formatPackedVertices();
    // The transform index: an instanced attribute over 0, 1, 2, ... offset by baseInstance.
    glVertexAttribIFormat(3, 1, GL_UNSIGNED_INT, 0);
    glVertexAttribBinding(3, 1);
    glVertexBindingDivisor(1, 1);
    glEnableVertexAttribArray(3);

    // Splats: the same vertices; per draw (baseInstance = its index in pointDraws) its
    // transform and diameter.
    glGenVertexArrays(1, &impl->pointVao);
    glBindVertexArray(impl->pointVao);
    formatPackedVertices();
    glVertexAttribIFormat(3, 1, GL_UNSIGNED_INT, offsetof(Impl::PointDraw, transform));
    glVertexAttribFormat(4, 1, GL_FLOAT, GL_FALSE, offsetof(Impl::PointDraw, pixels));
    for (GLuint a = 3; a < 5; ++a) {
        glVertexAttribBinding(a, 1);
        glEnableVertexAttribArray(a);
    }
    glVertexBindingDivisor(1, 1);
    glBindVertexArray(0);
    impl->bindArena();

    // Cubes: one CubeDraw per instance.
    glGenVertexArrays(1, &impl->cubeVao);
    glBindVertexArray(impl->cubeVao);
    glBindVertexBuffer(0, impl->ring[0].cubes, 0, sizeof(CubeDraw)); // rebound per batch
    glVertexBindingDivisor(0, 1);
    glVertexAttribFormat(0, 3, GL_FLOAT, GL_FALSE, offsetof(CubeDraw, boxMin));
    glVertexAttribFormat(1, 3, GL_FLOAT, GL_FALSE, offsetof(CubeDraw, boxMax));
    glVertexAttribIFormat(2, 1, GL_UNSIGNED_INT, offsetof(CubeDraw, transform));
    for (GLuint f = 0; f < 6; ++f)
        glVertexAttribFormat(3 + f, 4, GL_UNSIGNED_BYTE, GL_TRUE, static_cast<GLuint>(offsetof(CubeDraw, faces) + 4 * f));
    for (GLuint a = 0; a < 9; ++a) {
        glVertexAttribBinding(a, 0);
        glEnableVertexAttribArray(a);
    }
    glBindVertexArray(0);
    if (const GLenum error = glGetError(); error != GL_NO_ERROR)
        return Status(ErrorCode::Internal, "OpenGL error " + std::to_string(error) + " while creating the renderer");
    FF_RETURN_IF_ERROR(impl->warmPrograms());
    return std::unique_ptr<Renderer>(new Renderer(std::move(impl)));
}

// llvmpipe compiles a program's shaders for the state it is drawn with at the first draw with
// that state, not at link time: the geometry program's first draw took 21 ms here, as long as a
// street view of the city with occlusion culling takes to draw. Paid once, when the renderer is
// made, rather than by its first frame (a one-shot render's only one). Drawn into a 1x1 target
// that the first frame replaces or clears.
Status Renderer::Impl::warmPrograms() {
    FF_RETURN_IF_ERROR(ensureTarget(1, 1));
    glBindFramebuffer(GL_FRAMEBUFFER, framebuffer);
    glViewport(0, 0, 1, 1);
    glEnable(GL_FRAMEBUFFER_SRGB);
    glDisable(GL_CULL_FACE);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDepthMask(GL_TRUE);
    glDisable(GL_BLEND);
    const glm::mat4 identity(1.0f);
    DrawList list;
    list.transforms.push_back(identity);
    list.localEyes.push_back(glm::vec3(0.0f));
    uploadTransforms(list);
    // The arena's first triangle, whatever it holds (no page is resident yet).
    if (clustered)
        indexedCommands.push_back({3, 1, 0, 0, 0});
    else
        commands.push_back({3, 1, 0, 0});
    drawBatch(identity);
    list.cubes.push_back({glm::vec3(-0.5f), glm::vec3(0.5f), 0, {}});
    ensureOpacityTexture();
    for (const bool occlude : {false, true})
        for (const bool points : {false, true}) {
            list.cubesOcclude = occlude;
            list.cubesAsPoints = points;
            drawCubes(list, identity, 1.0f);
        }
    queries->warm();
    glFinish();
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    if (const GLenum error = glGetError(); error != GL_NO_ERROR)
        return Status(ErrorCode::Internal, "OpenGL error " + std::to_string(error) + " while warming the renderer's programs");
    return Status::ok();
}

void Renderer::Impl::ensureOpacityTexture() {
    if (opacityTexture)
        return;
    glGenTextures(1, &opacityTexture);
    glBindTexture(GL_TEXTURE_2D_ARRAY, opacityTexture);
    glTexStorage3D(GL_TEXTURE_2D_ARRAY, 1, GL_R32UI, targetWidth, targetHeight, 2);
}

Status Renderer::Impl::ensureTarget(int width, int height) {
    if (width == targetWidth && height == targetHeight && framebuffer)
        return Status::ok();
    GLint maxSize = 0;
    glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &maxSize);
    if (width > maxSize || height > maxSize)
        return Status(ErrorCode::InvalidArgument, "render target " + std::to_string(width) + "x" + std::to_string(height) +
                                                          " exceeds the GL limit of " + std::to_string(maxSize));
    glDeleteFramebuffers(1, &framebuffer);
    glDeleteTextures(1, &colorTexture);
    glDeleteTextures(1, &opacityTexture);
    glDeleteRenderbuffers(1, &depthBuffer);
    glDeleteFramebuffers(1, &presentFramebuffer);
    glDeleteTextures(1, &presentView);
    presentFramebuffer = presentView = opacityTexture = 0;
    glGenTextures(1, &colorTexture);
    glBindTexture(GL_TEXTURE_2D, colorTexture);
    glTexStorage2D(GL_TEXTURE_2D, 1, GL_SRGB8_ALPHA8, width, height);
    glGenRenderbuffers(1, &depthBuffer);
    glBindRenderbuffer(GL_RENDERBUFFER, depthBuffer);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, width, height);
    glGenFramebuffers(1, &framebuffer);
    glBindFramebuffer(GL_FRAMEBUFFER, framebuffer);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, colorTexture, 0);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depthBuffer);
    const GLenum complete = glCheckFramebufferStatus(GL_FRAMEBUFFER);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    if (complete != GL_FRAMEBUFFER_COMPLETE)
        return Status(ErrorCode::Internal, "render target framebuffer is incomplete");
    targetWidth = width;
    targetHeight = height;
    return Status::ok();
}

void Renderer::Impl::growArena() {
    const std::uint32_t grown = std::min(maxSlots, slotCount * 2);
    GLuint bigger = 0;
    glGenBuffers(1, &bigger);
    bufferData(bigger, slotBytes * grown, nullptr, GL_DYNAMIC_DRAW);
    glBindBuffer(GL_COPY_READ_BUFFER, arena);
    glBindBuffer(GL_COPY_WRITE_BUFFER, bigger);
    glCopyBufferSubData(GL_COPY_READ_BUFFER, GL_COPY_WRITE_BUFFER, 0, 0, slotBytes * slotCount);
    glDeleteBuffers(1, &arena);
    arena = bigger;
    bindArena();
    pageOfSlot.resize(grown, 0);
    slotBatch.resize(grown, 0);
    for (std::uint32_t s = grown; s-- > slotCount;)
        freeSlots.push_back(s);
    slotCount = grown;
}

Result<std::uint32_t> Renderer::Impl::residentSlot(const GeometryDraw& draw, FrameStats& stats) {
    const std::uint64_t page = draw.page;
    if (const auto it = slotOfPage.find(page); it != slotOfPage.end())
        return it->second;
    if (freeSlots.empty() && slotCount < maxSlots)
        growArena(); // slots already referenced by this batch keep their contents
    if (freeSlots.empty()) {
        // Evict the least recently used page not needed by the batch being assembled.
        const auto victim = lru.oldestWhereNot([this](std::uint64_t p) { return slotBatch[slotOfPage.at(p)] == batch; });
        if (!victim)
            return Status(ErrorCode::OutOfBudget, "batch full"); // caller flushes and retries
        const std::uint32_t slot = slotOfPage.at(*victim);
        slotOfPage.erase(*victim);
        lru.erase(*victim);
        freeSlots.push_back(slot);
    }
    // The draw carries the page's bytes, valid for the frame (the traversal found it Ready).
    const std::uint32_t slot = freeSlots.back();
    freeSlots.pop_back();
    const GLintptr base = static_cast<GLintptr>(slot) * slotBytes;
    if (clustered) {
        std::optional<DecodedGeometry> again; // a page decoded here, not by the stage
        const DecodedGeometry* decoded = decodedGeometry->decoded(page);
        if (decoded == nullptr) {
            const Result<CachedClusterPage> cached = CachedClusterPage::view({draw.payload, draw.payloadBytes});
            Result<DecodedGeometry> decodedHere =
                    cached ? decodeCachedPage(*cached, grids, maxDecodedBytes) : Result<DecodedGeometry>(cached.status());
            if (!decodedHere) {
                freeSlots.push_back(slot);
                return decodedHere.status().withContext("page " + std::to_string(page));
            }
            decoded = &again.emplace(std::move(*decodedHere));
            ++stats.pagesDecodedOnDraw;
        }
        if (decoded->size() > static_cast<std::uint64_t>(slotBytes)) {
            freeSlots.push_back(slot);
            return Status(ErrorCode::Corrupt, "page " + std::to_string(page) + ": decodes past its slot");
        }
        const auto vertexBytes = static_cast<GLsizeiptr>(decoded->vertices().size_bytes());
        bufferSubData(arena, base, vertexBytes, decoded->vertices().data());
        bufferSubData(arena, base + vertexBytes, static_cast<GLsizeiptr>(decoded->indices().size()),
                      decoded->indices().data());
        decodedGeometry->uploaded(page);
    } else {
        bufferSubData(arena, base, slotBytes, draw.payload);
    }
    slotOfPage[page] = slot;
    pageOfSlot[slot] = page;
    ++stats.pagesUploaded;
    return slot;
}

void Renderer::Impl::bindArena() {
    glBindVertexArray(geometryVao);
    glBindVertexBuffer(0, arena, 0, sizeof(storage::PackedVertex));
    if (clustered)
        glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, arena); // VAO state
    if (pointVao != 0) {
        glBindVertexArray(pointVao);
        glBindVertexBuffer(0, arena, 0, sizeof(storage::PackedVertex));
    }
    glBindVertexArray(0);
}

bool Renderer::Impl::appendClusterCommands(const GeometryDraw& draw, std::uint32_t slot) {
    const Result<CachedClusterPage> page = CachedClusterPage::view({draw.payload, draw.payloadBytes});
    const auto clusters = page ? page->clusters(draw.first, draw.count) : std::span<const storage::IndexedCluster>{};
    if (clusters.size() != draw.count || draw.count == 0)
        return false;
    const std::uint64_t base = std::uint64_t{slot} * static_cast<std::uint64_t>(slotBytes);
    const std::uint64_t indices = base + std::uint64_t{page->vertexCount()} * sizeof(storage::PackedVertex);
    for (const storage::IndexedCluster& cluster : clusters) {
        if (cluster.info.points()) {
            pointCommands.push_back(
                    {cluster.info.vertexCount, 1, slot * verticesPerSlot + cluster.firstVertex,
                     static_cast<GLuint>(pointDraws.size())});
            pointDraws.push_back({draw.transform, draw.pointPixels > 0.0f ? draw.pointPixels : splats.pixels});
            continue;
        }
        indexedCommands.push_back(
                {cluster.info.triangleCount * 3,
                 1,
                 static_cast<GLuint>(indices + cluster.firstIndex),
                 static_cast<GLint>(slot * verticesPerSlot + cluster.firstVertex),
                 draw.transform});
    }
    return true;
}

void Renderer::Impl::useGeometryProgram(GLuint program, const glm::mat4& viewProjection) {
    glUseProgram(program);
    glUniformMatrix4fv(glGetUniformLocation(program, "uViewProjection"), 1, GL_FALSE, glm::value_ptr(viewProjection));
    glUniform3f(glGetUniformLocation(program, "uLightDirection"), storage::kLightDirection[0],
                storage::kLightDirection[1], storage::kLightDirection[2]);
    glUniform1f(glGetUniformLocation(program, "uAmbient"), storage::kAmbient);
    glUniform1f(glGetUniformLocation(program, "uDiffuse"), storage::kDiffuse);
    glUniform1f(glGetUniformLocation(program, "uPointScale"), static_cast<float>(frameSupersample));
}

void Renderer::Impl::drawBatch(const glm::mat4& viewProjection) {
    if (commands.empty() && indexedCommands.empty() && pointCommands.empty())
        return;
    // Triangles' commands, then the points' (4-byte aligned: both are arrays of GLuint).
    const auto bytes = clustered ? static_cast<GLsizeiptr>(indexedCommands.size() * sizeof(IndexedCommand))
                                 : static_cast<GLsizeiptr>(commands.size() * sizeof(IndirectCommand));
    const auto pointBytes = static_cast<GLsizeiptr>(pointCommands.size() * sizeof(IndirectCommand));
    BatchBuffers& set = current();
    ensureCapacity(set.indirect, set.indirectCap, bytes + pointBytes);
    if (clustered)
        bufferSubData(set.indirect, 0, bytes, indexedCommands.data());
    else
        bufferSubData(set.indirect, 0, bytes, commands.data());
    if (pointBytes > 0)
        bufferSubData(set.indirect, bytes, pointBytes, pointCommands.data());
    useGeometryProgram(geometryProgram, viewProjection);
    glBindVertexArray(geometryVao);
    glBindBuffer(GL_DRAW_INDIRECT_BUFFER, set.indirect);
    if (clustered && !indexedCommands.empty())
        glMultiDrawElementsIndirect(GL_TRIANGLES, GL_UNSIGNED_BYTE, nullptr, static_cast<GLsizei>(indexedCommands.size()), 0);
    else if (!clustered)
        glMultiDrawArraysIndirect(GL_TRIANGLES, nullptr, static_cast<GLsizei>(commands.size()), 0);
    if (!pointCommands.empty()) {
        const auto drawBytes = static_cast<GLsizeiptr>(pointDraws.size() * sizeof(PointDraw));
        ensureCapacity(set.pointDraws, set.pointDrawsCap, drawBytes);
        bufferSubData(set.pointDraws, 0, drawBytes, pointDraws.data());
        if (splats.round)
            useGeometryProgram(roundSplatProgram, viewProjection);
        glBindVertexArray(pointVao);
        glBindVertexBuffer(1, set.pointDraws, 0, sizeof(PointDraw));
        glEnable(GL_PROGRAM_POINT_SIZE);
        glMultiDrawArraysIndirect(GL_POINTS, reinterpret_cast<const void*>(static_cast<std::uintptr_t>(bytes)),
                                  static_cast<GLsizei>(pointCommands.size()), 0);
        glDisable(GL_PROGRAM_POINT_SIZE);
    }
    commands.clear();
    indexedCommands.clear();
    pointCommands.clear();
    pointDraws.clear();
    ++batch;
}

Status Renderer::Impl::drawGeometry(const DrawList& list, const glm::mat4& viewProjection, FrameStats& stats) {
    ++batch;
    splats = list.splats;
    for (const GeometryDraw& draw : list.geometry) {
        Result<std::uint32_t> slot = residentSlot(draw, stats);
        if (!slot && slot.status().code() == ErrorCode::OutOfBudget) {
            drawBatch(viewProjection); // frees this batch's pins
            slot = residentSlot(draw, stats);
        }
        if (!slot) {
            commands.clear();
            indexedCommands.clear();
            pointCommands.clear();
            pointDraws.clear();
            return slot.status();
        }
        slotBatch[*slot] = batch;
        lru.touch(draw.page);
        if (!clustered)
            commands.push_back({draw.count * 3, 1, *slot * verticesPerSlot + draw.first * 3, draw.transform});
        else if (!appendClusterCommands(draw, *slot)) {
            indexedCommands.clear();
            pointCommands.clear();
            pointDraws.clear();
            return Status(ErrorCode::Corrupt, "page " + std::to_string(draw.page) + ": not a cached cluster page");
        }
    }
    drawBatch(viewProjection);
    return Status::ok();
}

void Renderer::Impl::bindCubes(const DrawList& list, GLuint program, const glm::mat4& viewProjection) {
    const auto bytes = static_cast<GLsizeiptr>(list.cubes.size() * sizeof(CubeDraw));
    cubeSlot = (cubeSlot + 1) % kBatchBufferSets;
    BatchBuffers& set = ring[cubeSlot];
    ensureCapacity(set.cubes, set.cubesCap, bytes);
    bufferSubData(set.cubes, 0, bytes, list.cubes.data());
    glUseProgram(program);
    glUniformMatrix4fv(glGetUniformLocation(program, "uViewProjection"), 1, GL_FALSE, glm::value_ptr(viewProjection));
    glBindVertexArray(cubeVao);
    glBindVertexBuffer(0, set.cubes, 0, sizeof(CubeDraw));
}

void Renderer::Impl::drawBoundCubes(const DrawList& list, GLuint program, float pixelScale) {
    if (list.cubesAsPoints) {
        glUniform1f(glGetUniformLocation(program, "uPixelScale"), pixelScale);
        glEnable(GL_PROGRAM_POINT_SIZE);
        glDrawArraysInstanced(GL_POINTS, 0, 1, static_cast<GLsizei>(list.cubes.size()));
        glDisable(GL_PROGRAM_POINT_SIZE);
    } else {
        glDrawArraysInstanced(GL_TRIANGLES, 0, 18, static_cast<GLsizei>(list.cubes.size()));
    }
}

void Renderer::Impl::drawCubes(const DrawList& list, const glm::mat4& viewProjection, float pixelScale) {
    if (list.cubes.empty())
        return;
    const GLuint program = list.cubesOcclude ? (list.cubesAsPoints ? cubePointOccluderProgram : cubeOccluderProgram)
                                             : (list.cubesAsPoints ? cubePointProgram : cubeProgram);
    bindCubes(list, program, viewProjection);
    if (list.cubesOcclude) {
        // Depth only; the opacity sums of earlier batches must be visible to this one's loads.
        glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
        glBindImageTexture(0, opacityTexture, 0, GL_TRUE, 0, GL_READ_WRITE, GL_R32UI);
        glUniform1ui(glGetUniformLocation(program, "uOccludes"), frameOccludes);
        glUniform1f(glGetUniformLocation(program, "uDepthBias"), kOccluderDepthBias);
        glColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
    } else {
        glEnable(GL_BLEND);
        glBlendFunc(GL_ONE, GL_ONE_MINUS_SRC_ALPHA); // premultiplied "over", back to front
        glDepthMask(GL_FALSE);
    }
    drawBoundCubes(list, program, pixelScale);
    glDepthMask(GL_TRUE);
    glDisable(GL_BLEND);
    glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
}

void Renderer::Impl::uploadTransforms(const DrawList& list) {
    // Transforms, their normal matrices and the eye in each frame.
    const auto transformCount = static_cast<GLsizeiptr>(list.transforms.size());
    normalScratch.resize(list.transforms.size());
    eyeScratch.resize(list.transforms.size());
    for (std::size_t i = 0; i < list.transforms.size(); ++i) {
        normalScratch[i] = glm::mat4(glm::transpose(glm::inverse(glm::mat3(list.transforms[i]))));
        eyeScratch[i] = glm::vec4(list.localEyes[i], 1.0f);
    }
    BatchBuffers& set = current();
    ensureCapacity(set.transforms, set.transformsCap, transformCount * static_cast<GLsizeiptr>(sizeof(glm::mat4)));
    ensureCapacity(set.normalMatrices, set.normalsCap, transformCount * static_cast<GLsizeiptr>(sizeof(glm::mat4)));
    ensureCapacity(set.localEyes, set.eyesCap, transformCount * static_cast<GLsizeiptr>(sizeof(glm::vec4)));
    bufferSubData(set.transforms, 0, transformCount * static_cast<GLsizeiptr>(sizeof(glm::mat4)), list.transforms.data());
    bufferSubData(set.normalMatrices, 0, transformCount * static_cast<GLsizeiptr>(sizeof(glm::mat4)), normalScratch.data());
    bufferSubData(set.localEyes, 0, transformCount * static_cast<GLsizeiptr>(sizeof(glm::vec4)), eyeScratch.data());
    if (iotaCap < transformCount * static_cast<GLsizeiptr>(sizeof(GLuint))) {
        std::vector<GLuint> values(static_cast<std::size_t>(std::max<GLsizeiptr>(transformCount * 2, 1024)));
        for (std::size_t i = 0; i < values.size(); ++i)
            values[i] = static_cast<GLuint>(i);
        iotaCap = static_cast<GLsizeiptr>(values.size() * sizeof(GLuint));
        bufferData(iota, iotaCap, values.data(), GL_STATIC_DRAW);
        glBindVertexArray(geometryVao);
        glBindVertexBuffer(1, iota, 0, sizeof(GLuint));
        glBindVertexArray(0);
    }
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, set.transforms);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, set.normalMatrices);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, set.localEyes);
}

Status Renderer::beginFrame(const FrameContext& frame, FrameOutput output, FrameStats& stats) {
    Impl& s = *mImpl;
    const int supersample = output == FrameOutput::Image ? frame.supersample : 1;
    if (frame.width <= 0 || frame.height <= 0 || supersample <= 0)
        return Status(ErrorCode::InvalidArgument, "image size and supersampling must be positive");
    const auto start = std::chrono::steady_clock::now();
    s.output = output;
    s.frameWidth = frame.width;
    s.frameHeight = frame.height;
    s.frameSupersample = supersample;
    s.uploadLimit = frame.budgets.gpuUploadsPerFrame;
    s.admitted.clear();
    const int sampleWidth = frame.width * supersample;
    const int sampleHeight = frame.height * supersample;
    FF_RETURN_IF_ERROR(s.ensureTarget(sampleWidth, sampleHeight));
    s.frameViewProjection = frame.camera.projection(static_cast<float>(frame.width) / static_cast<float>(frame.height)) *
                       frame.camera.view();
    s.framePixelScale = frame.camera.pixelScale(static_cast<float>(sampleHeight));
    s.queries->beginFrame(s.frameViewProjection);
    s.occlusionBackend = frame.occlusion.backend;
    s.frameOccludes = occludingOpacity(frame.occlusion.opacityThreshold);
    s.pyramidTests.beginFrame(s.frameViewProjection, s.framebuffer, sampleWidth, sampleHeight);

    glBindFramebuffer(GL_FRAMEBUFFER, s.framebuffer);
    glViewport(0, 0, sampleWidth, sampleHeight);
    glEnable(GL_FRAMEBUFFER_SRGB); // the clear colour and every blend are in linear space
    glDisable(GL_CULL_FACE);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDepthMask(GL_TRUE);
    glDisable(GL_BLEND);
    // An Image is transparent: the background is composited on the CPU, after the resolve, so
    // coverage survives as alpha. A window starts as the opaque background, which cubes blend
    // over on the GPU (in linear space, like resolveFramebuffer does on the CPU).
    const glm::vec4 clearColor =
            output == FrameOutput::Image ? glm::vec4(0.0f) : glm::vec4(s.options.backgroundLinear, 1.0f);
    glClearColor(clearColor.r, clearColor.g, clearColor.b, clearColor.a);
    glClearDepth(1.0);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    if (frame.occlusion.enabled && frame.occlusion.cubesOcclude) {
        s.ensureOpacityTexture(); // made for the frames that use it
        const GLuint nothing = 0;
        glClearTexImage(s.opacityTexture, 0, GL_RED_INTEGER, GL_UNSIGNED_INT, &nothing);
    }
    stats.drawMs += millisecondsSince(start);
    return Status::ok();
}

Status Renderer::draw(const DrawList& batch, FrameStats& stats) {
    Impl& s = *mImpl;
    const auto start = std::chrono::steady_clock::now();
    s.ringSlot = (s.ringSlot + 1) % Impl::kBatchBufferSets;
    s.uploadTransforms(batch);
    FF_RETURN_IF_ERROR(s.drawGeometry(batch, s.frameViewProjection, stats));
    if (!batch.geometry.empty() || (batch.cubesOcclude && !batch.cubes.empty()))
        s.pyramidTests.depthDrawn();
    s.drawCubes(batch, s.frameViewProjection, s.framePixelScale);
    stats.drawMs += millisecondsSince(start);
    return Status::ok();
}

BatchVisibility Renderer::visibleParts(const DrawList& batch) {
    Impl& s = *mImpl;
    BatchVisibility visible;
    std::uint64_t triangles = 0;
    for (const GeometryDraw& draw : batch.geometry)
        triangles += draw.triangles;
    visible.triangles.assign(triangles, true);
    visible.cubes.assign(batch.cubes.size(), true);
    if (!s.visibleTriangleProgram) {
        auto program = linkGlProgram({gl::kGeometryVertexShader}, gl::kVisibleTriangleFragmentShader);
        auto cube = linkGlProgram({gl::kCubeShaderInputs, gl::kCubeVertexShader}, gl::kVisibleCubeFragmentShader);
        auto point = linkGlProgram({gl::kCubeShaderInputs, gl::kCubePointVertexShader}, gl::kVisibleCubeFragmentShader);
        if (!program || !cube || !point) {
            for (const auto* linked : {&program, &cube, &point})
                if (*linked)
                    glDeleteProgram(**linked);
            return visible; // unknown: everything shows
        }
        s.visibleTriangleProgram = *program;
        s.visibleCubeProgram = *cube;
        s.visibleCubePointProgram = *point;
        glGenBuffers(1, &s.visibleBits);
    }
    const std::uint64_t bits = triangles + batch.cubes.size();
    const auto words = static_cast<GLsizeiptr>((bits + 31) / 32);
    if (words == 0)
        return visible;
    ensureCapacity(s.visibleBits, s.visibleBitsCap, words * static_cast<GLsizeiptr>(sizeof(GLuint)));
    const GLuint zero = 0;
    glClearNamedBufferSubData(s.visibleBits, GL_R32UI, 0, words * static_cast<GLsizeiptr>(sizeof(GLuint)), GL_RED_INTEGER,
                              GL_UNSIGNED_INT, &zero);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, s.visibleBits);

    glBindFramebuffer(GL_FRAMEBUFFER, s.framebuffer); // the finished frame's depth
    glViewport(0, 0, s.frameWidth * s.frameSupersample, s.frameHeight * s.frameSupersample);
    s.ringSlot = (s.ringSlot + 1) % Impl::kBatchBufferSets;
    s.uploadTransforms(batch);
    glColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
    glDepthMask(GL_FALSE);
    glUseProgram(s.visibleTriangleProgram);
    glUniformMatrix4fv(glGetUniformLocation(s.visibleTriangleProgram, "uViewProjection"), 1, GL_FALSE,
                       glm::value_ptr(s.frameViewProjection));
    const GLint firstBit = glGetUniformLocation(s.visibleTriangleProgram, "uFirstBit");
    glBindVertexArray(s.geometryVao);
    glDepthFunc(GL_EQUAL);
    std::vector<bool> resident(batch.geometry.size(), false);
    std::uint64_t bit = 0;
    for (std::size_t i = 0; i < batch.geometry.size(); ++i) {
        const GeometryDraw& draw = batch.geometry[i];
        const auto slot = s.slotOfPage.find(draw.page);
        if (slot != s.slotOfPage.end() && !s.clustered) {
            resident[i] = true;
            glUniform1ui(firstBit, static_cast<GLuint>(bit));
            glDrawArraysInstancedBaseInstance(
                    GL_TRIANGLES,
                    static_cast<GLint>(slot->second * s.verticesPerSlot + draw.first * 3),
                    static_cast<GLsizei>(draw.count * 3),
                    1,
                    draw.transform);
        } else if (slot != s.slotOfPage.end() && s.appendClusterCommands(draw, slot->second)) {
            // A draw per cluster: gl_PrimitiveID counts from 0 in each.
            resident[i] = true;
            GLuint clusterBit = static_cast<GLuint>(bit);
            for (const IndexedCommand& c : s.indexedCommands) {
                glUniform1ui(firstBit, clusterBit);
                glDrawElementsInstancedBaseVertexBaseInstance(
                        GL_TRIANGLES,
                        static_cast<GLsizei>(c.count),
                        GL_UNSIGNED_BYTE,
                        reinterpret_cast<const void*>(static_cast<std::uintptr_t>(c.firstIndex)),
                        1,
                        c.baseVertex,
                        c.baseInstance);
                clusterBit += c.count / 3;
            }
            s.indexedCommands.clear();
            s.pointCommands.clear(); // splats have no triangle bits to set (the oracle keeps them all)
            s.pointDraws.clear();
        }
        bit += draw.triangles;
    }
    if (!batch.cubes.empty()) {
        const GLuint program = batch.cubesAsPoints ? s.visibleCubePointProgram : s.visibleCubeProgram;
        s.bindCubes(batch, program, s.frameViewProjection);
        glUniform1ui(glGetUniformLocation(program, "uFirstBit"), static_cast<GLuint>(triangles));
        glDepthFunc(GL_LESS);
        s.drawBoundCubes(batch, program, s.framePixelScale);
    }
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    std::vector<GLuint> shown(static_cast<std::size_t>(words));
    glGetNamedBufferSubData(s.visibleBits, 0, words * static_cast<GLsizeiptr>(sizeof(GLuint)), shown.data());
    const auto isSet = [&](std::uint64_t b) { return (shown[b >> 5] >> (b & 31u)) & 1u; };
    bit = 0;
    for (std::size_t i = 0; i < batch.geometry.size(); ++i) {
        for (std::uint32_t t = 0; t < batch.geometry[i].triangles; ++t, ++bit)
            visible.triangles[bit] = !resident[i] || isSet(bit);
    }
    for (std::size_t c = 0; c < batch.cubes.size(); ++c)
        visible.cubes[c] = isSet(triangles + c);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glDepthFunc(GL_LESS);
    glDepthMask(GL_TRUE);
    glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    return visible;
}

QueryTicket Renderer::issue(std::span<const OcclusionBox> group) {
    Impl& s = *mImpl;
    return s.occlusionBackend == OcclusionBackend::Queries ? s.queries->issue(group) : s.pyramidTests.issue(group);
}

void Renderer::submit() {
    Impl& s = *mImpl;
    if (s.occlusionBackend == OcclusionBackend::Queries)
        glFlush();
    else
        s.pyramidTests.submit();
}

bool Renderer::ready(QueryTicket ticket) {
    Impl& s = *mImpl;
    return s.occlusionBackend == OcclusionBackend::Queries ? s.queries->ready(ticket) : s.pyramidTests.ready(ticket);
}

bool Renderer::anyVisible(QueryTicket ticket) {
    Impl& s = *mImpl;
    return s.occlusionBackend == OcclusionBackend::Queries ? s.queries->anyVisible(ticket)
                                                          : s.pyramidTests.anyVisible(ticket);
}

bool Renderer::admit(std::uint64_t geometryPage) {
    Impl& s = *mImpl;
    if (s.slotOfPage.contains(geometryPage) || s.admitted.contains(geometryPage))
        return true;
    // Asked before the upload budget, so the pages it refuses this frame are decoded for the next.
    if (s.clustered && !s.decodedGeometry->prepare(geometryPage) && !s.decodeOnDraw)
        return false;
    if (s.uploadLimit == 0 && !s.clustered)
        return true;
    // Format 2 remembers what it admitted even without a limit: once uploaded, the decoded copy
    // is gone, and the answer must stay yes for the rest of the frame.
    if (s.uploadLimit != 0 && s.admitted.size() >= s.uploadLimit)
        return false;
    s.admitted.insert(geometryPage);
    return true;
}

void Renderer::setDecodeOnDraw(bool on) noexcept {
    mImpl->decodeOnDraw = on;
}

Result<Image> Renderer::finishImage(FrameStats& stats) {
    Impl& s = *mImpl;
    const auto start = std::chrono::steady_clock::now();
    glFinish(); // the frame time is the time until the GPU is done, not until submission
    stats.drawMs += millisecondsSince(start);

    const int targetWidth = s.frameWidth * s.frameSupersample;
    const int targetHeight = s.frameHeight * s.frameSupersample;
    s.readback.resize(static_cast<std::size_t>(targetWidth) * static_cast<std::size_t>(targetHeight) * 4);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, targetWidth, targetHeight, GL_RGBA, GL_UNSIGNED_BYTE, s.readback.data());
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    if (const GLenum error = glGetError(); error != GL_NO_ERROR)
        return Status(ErrorCode::Internal, "OpenGL error " + std::to_string(error) + " while rendering");
    return resolveFramebuffer(s.readback, s.frameWidth, s.frameHeight, s.frameSupersample, s.options.backgroundLinear);
}

// ---- Presenting to a window ---------------------------------------------------------------
// The frame is drawn exactly as for render(), except that the target starts as the opaque
// background, so cubes blend over it on the GPU (in linear space, like resolveFramebuffer
// does on the CPU). It is then copied byte for byte to the default framebuffer through an
// RGBA8 view of the sRGB texture: a blit from a UNORM source with GL_FRAMEBUFFER_SRGB off
// converts nothing on either side, whatever the window's framebuffer encoding is, so the
// window shows the same sRGB bytes a PNG from render() holds.

Status Renderer::Impl::ensurePresentSource() {
    if (presentFramebuffer)
        return Status::ok();
    glGenTextures(1, &presentView);
    glTextureView(presentView, GL_TEXTURE_2D, colorTexture, GL_RGBA8, 0, 1, 0, 1);
    glGenFramebuffers(1, &presentFramebuffer);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, presentFramebuffer);
    glFramebufferTexture2D(GL_READ_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, presentView, 0);
    const GLenum complete = glCheckFramebufferStatus(GL_READ_FRAMEBUFFER);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
    if (complete != GL_FRAMEBUFFER_COMPLETE)
        return Status(ErrorCode::Internal, "present framebuffer is incomplete");
    return Status::ok();
}

Status Renderer::finishPresent(FrameStats& stats) {
    Impl& s = *mImpl;
    const auto start = std::chrono::steady_clock::now();
    FF_RETURN_IF_ERROR(s.ensurePresentSource());
    glDisable(GL_FRAMEBUFFER_SRGB);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, s.presentFramebuffer);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
    glBlitFramebuffer(0, 0, s.frameWidth, s.frameHeight, 0, 0, s.frameWidth, s.frameHeight, GL_COLOR_BUFFER_BIT,
                      GL_NEAREST);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    // Submission only: the swap that follows waits for the GPU, and the caller times frames.
    stats.drawMs += millisecondsSince(start);
    if (const GLenum error = glGetError(); error != GL_NO_ERROR)
        return Status(ErrorCode::Internal, "OpenGL error " + std::to_string(error) + " while presenting");
    return Status::ok();
}

std::uint64_t Renderer::residentBytes() const noexcept {
    return static_cast<std::uint64_t>(mImpl->slotOfPage.size()) * static_cast<std::uint64_t>(mImpl->slotBytes);
}

} // namespace ff::runtime
