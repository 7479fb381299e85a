// Color-cube baking and compositing. Chamberlain, DeRose, Lischinski, Salesin, Snyder:
// "Fast Rendering of Complex Environments Using a Spatial Hierarchy", GI '96, §4 and Fig. 3.

#include <ff/builder/ColorCube.h>
#include <ff/storage/ShadingModel.h>
#include <ff/storage/VertexCodec.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace ff::builder {

namespace {

constexpr float kInfinity = std::numeric_limits<float>::infinity();

glm::vec3 shadedVertexColor(const storage::PackedVertex& v) {
    const auto n = storage::decodeOctNormal(v.normalOct);
    const float light = storage::isUnlitNormal(v.normalOct) ? storage::kUnlitShading
                                                            : storage::shadingFactor(n[0], n[1], n[2]);
    return glm::vec3(
                   storage::srgb8ToLinear(v.color[0]),
                   storage::srgb8ToLinear(v.color[1]),
                   storage::srgb8ToLinear(v.color[2])) *
           light;
}

glm::vec3 toVec3(const std::array<float, 3>& a) { return {a[0], a[1], a[2]}; }

// The underlay colour of sample (i, j) of a face. With an even resolution the quadrant boundaries
// fall between samples. With an odd one the middle row and column lie on them: those samples take
// the mean of the quadrants they touch, so every quadrant keeps the weight 1/4 that Fig. 3's
// average gives it.
glm::vec4 underlayColor(const std::array<glm::vec4, 4>& quadrants, int i, int j, int resolution) {
    const int half = resolution / 2;
    const bool odd = resolution % 2 == 1;
    const bool middleU = odd && i == half;
    const bool middleV = odd && j == half;
    const std::size_t qu = i < half ? 0 : 1;
    const std::size_t qv = j < half ? 0 : 1;
    if (middleU && middleV)
        return 0.25f * (quadrants[0] + quadrants[1] + quadrants[2] + quadrants[3]);
    if (middleU)
        return 0.5f * (quadrants[2 * qv] + quadrants[1 + 2 * qv]);
    if (middleV)
        return 0.5f * (quadrants[qu] + quadrants[qu + 2]);
    return quadrants[qu + 2 * qv];
}

} // namespace

std::array<std::array<std::uint8_t, 4>, storage::kCubeFaceCount> quantizeCube(const ColorCube& cube) {
    std::array<std::array<std::uint8_t, 4>, storage::kCubeFaceCount> out{};
    for (int f = 0; f < storage::kCubeFaceCount; ++f) {
        const glm::vec4& c = cube.faces[static_cast<std::size_t>(f)];
        auto& o = out[static_cast<std::size_t>(f)];
        o = {storage::toUnorm8(c.r), storage::toUnorm8(c.g), storage::toUnorm8(c.b), storage::toUnorm8(c.a)};
        // Premultiplied: a colour channel can never exceed alpha after rounding either.
        for (int k = 0; k < 3; ++k)
            o[static_cast<std::size_t>(k)] = std::min(o[static_cast<std::size_t>(k)], o[3]);
    }
    return out;
}

ColorCube dequantizeCube(const std::array<std::array<std::uint8_t, 4>, storage::kCubeFaceCount>& bytes) {
    ColorCube cube;
    for (std::size_t f = 0; f < bytes.size(); ++f)
        cube.faces[f] = glm::vec4(bytes[f][0], bytes[f][1], bytes[f][2], bytes[f][3]) / 255.0f;
    return cube;
}

QuadrantColors compositeOctantQuadrants(const std::array<const ColorCube*, 8>& children) {
    QuadrantColors out{};
    for (int f = 0; f < storage::kCubeFaceCount; ++f) {
        const int axis = f / 2;
        const int side = f % 2; // 1: the viewer is on the + side, so the + half is in front
        const int u = faceAxisU(axis);
        const int v = faceAxisV(axis);
        for (int qv = 0; qv < 2; ++qv) {
            for (int qu = 0; qu < 2; ++qu) {
                const int inPlane = (qu << u) | (qv << v);
                const ColorCube* front = children[static_cast<std::size_t>(inPlane | (side << axis))];
                const ColorCube* back = children[static_cast<std::size_t>(inPlane | ((1 - side) << axis))];
                const glm::vec4 frontColor = front ? front->faces[static_cast<std::size_t>(f)] : glm::vec4(0.0f);
                const glm::vec4 backColor = back ? back->faces[static_cast<std::size_t>(f)] : glm::vec4(0.0f);
                out[static_cast<std::size_t>(f)][static_cast<std::size_t>(qu + 2 * qv)] = over(frontColor, backColor);
            }
        }
    }
    return out;
}

ColorCube compositeOctants(const std::array<const ColorCube*, 8>& children) {
    const QuadrantColors quadrants = compositeOctantQuadrants(children);
    ColorCube cube;
    for (std::size_t f = 0; f < quadrants.size(); ++f) {
        glm::vec4 sum(0.0f);
        for (const glm::vec4& q : quadrants[f])
            sum += q;
        cube.faces[f] = sum * 0.25f;
    }
    return cube;
}

CubeBaker::CubeBaker(int resolution) : mResolution(std::max(resolution, 2)) {
    const auto samples = static_cast<std::size_t>(mResolution * mResolution);
    for (AxisGrid& grid : mGrids) {
        grid.minDepth.resize(samples);
        grid.maxDepth.resize(samples);
        grid.minColor.resize(samples);
        grid.maxColor.resize(samples);
    }
    reset(glm::vec3(0.0f), glm::vec3(1.0f));
}

void CubeBaker::reset(const glm::vec3& cellMin, const glm::vec3& cellMax) {
    mCellMin = cellMin;
    mCellMax = cellMax;
    for (AxisGrid& grid : mGrids) {
        std::fill(grid.minDepth.begin(), grid.minDepth.end(), kInfinity);
        std::fill(grid.maxDepth.begin(), grid.maxDepth.end(), -kInfinity);
    }
    for (auto& fragments : mBoxFragments)
        fragments.clear();
}

void CubeBaker::addTriangles(std::span<const storage::PackedTriangle> triangles) {
    for (const storage::PackedTriangle& t : triangles) {
        const std::array<glm::vec3, 3> p = {
                toVec3(t.vertices[0].position), toVec3(t.vertices[1].position), toVec3(t.vertices[2].position)};
        const std::array<glm::vec3, 3> c = {
                shadedVertexColor(t.vertices[0]), shadedVertexColor(t.vertices[1]), shadedVertexColor(t.vertices[2])};
        for (int axis = 0; axis < 3; ++axis)
            rasterizeTriangle(axis, p, c);
    }
}

// Samples sit at the centres of a resolution x resolution grid over the face. A sample is
// covered when it lies inside the triangle's projection (edges inclusive: the nearest-surface
// rule makes double hits on shared edges harmless).
void CubeBaker::rasterizeTriangle(
        int axis, const std::array<glm::vec3, 3>& p, const std::array<glm::vec3, 3>& c) {
    const int u = faceAxisU(axis);
    const int v = faceAxisV(axis);
    const float res = static_cast<float>(mResolution);
    const float scaleU = res / std::max(mCellMax[u] - mCellMin[u], 1e-30f);
    const float scaleV = res / std::max(mCellMax[v] - mCellMin[v], 1e-30f);
    std::array<glm::vec2, 3> q;
    for (int i = 0; i < 3; ++i)
        q[static_cast<std::size_t>(i)] = {
                (p[static_cast<std::size_t>(i)][u] - mCellMin[u]) * scaleU - 0.5f,
                (p[static_cast<std::size_t>(i)][v] - mCellMin[v]) * scaleV - 0.5f};
    const float area = (q[1].x - q[0].x) * (q[2].y - q[0].y) - (q[2].x - q[0].x) * (q[1].y - q[0].y);
    if (!(std::fabs(area) > 1e-12f))
        return; // edge-on: invisible in this projection
    const float minX = std::min({q[0].x, q[1].x, q[2].x});
    const float maxX = std::max({q[0].x, q[1].x, q[2].x});
    const float minY = std::min({q[0].y, q[1].y, q[2].y});
    const float maxY = std::max({q[0].y, q[1].y, q[2].y});
    const int i0 = std::max(0, static_cast<int>(std::ceil(minX)));
    const int i1 = std::min(mResolution - 1, static_cast<int>(std::floor(maxX)));
    const int j0 = std::max(0, static_cast<int>(std::ceil(minY)));
    const int j1 = std::min(mResolution - 1, static_cast<int>(std::floor(maxY)));
    if (i0 > i1 || j0 > j1)
        return;
    const float invArea = 1.0f / area;
    constexpr float kEdgeTolerance = -1e-6f;
    AxisGrid& grid = mGrids[static_cast<std::size_t>(axis)];
    for (int j = j0; j <= j1; ++j) {
        for (int i = i0; i <= i1; ++i) {
            const glm::vec2 s(static_cast<float>(i), static_cast<float>(j));
            const float w0 = ((q[1].x - s.x) * (q[2].y - s.y) - (q[2].x - s.x) * (q[1].y - s.y)) * invArea;
            const float w1 = ((q[2].x - s.x) * (q[0].y - s.y) - (q[0].x - s.x) * (q[2].y - s.y)) * invArea;
            const float w2 = 1.0f - w0 - w1;
            if (w0 < kEdgeTolerance || w1 < kEdgeTolerance || w2 < kEdgeTolerance)
                continue;
            const float depth = w0 * p[0][axis] + w1 * p[1][axis] + w2 * p[2][axis];
            const auto index = static_cast<std::size_t>(j * mResolution + i);
            if (depth < grid.minDepth[index]) {
                grid.minDepth[index] = depth;
                grid.minColor[index] = w0 * c[0] + w1 * c[1] + w2 * c[2];
            }
            if (depth > grid.maxDepth[index]) {
                grid.maxDepth[index] = depth;
                grid.maxColor[index] = w0 * c[0] + w1 * c[1] + w2 * c[2];
            }
        }
    }
}

void CubeBaker::addBox(
        const glm::mat4& transform,
        const glm::vec3& boxMin,
        const glm::vec3& boxMax,
        const ColorCube& cube) {
    std::array<glm::vec3, 8> corners;
    for (int k = 0; k < 8; ++k) {
        const glm::vec3 local(
                (k & 1) ? boxMax.x : boxMin.x, (k & 2) ? boxMax.y : boxMin.y, (k & 4) ? boxMax.z : boxMin.z);
        corners[static_cast<std::size_t>(k)] = glm::vec3(transform * glm::vec4(local, 1.0f));
    }
    const glm::vec3 center = glm::vec3(transform * glm::vec4(0.5f * (boxMin + boxMax), 1.0f));
    const glm::mat3 normalMatrix = glm::transpose(glm::inverse(glm::mat3(transform)));
    for (int localFace = 0; localFace < storage::kCubeFaceCount; ++localFace) {
        const glm::vec4& color = cube.faces[static_cast<std::size_t>(localFace)];
        if (!(color.a > 0.0f))
            continue;
        const int localAxis = localFace / 2;
        const int localSide = localFace % 2;
        glm::vec3 localNormal(0.0f);
        localNormal[localAxis] = localSide ? 1.0f : -1.0f;
        const glm::vec3 worldNormal = normalMatrix * localNormal;
        // The four corners of the local face, in winding order around it.
        const int a = faceAxisU(localAxis);
        const int b = faceAxisV(localAxis);
        const int sideBit = localSide << localAxis;
        const std::array<glm::vec3, 4> faceCorners = {
                corners[static_cast<std::size_t>(sideBit)],
                corners[static_cast<std::size_t>(sideBit | (1 << a))],
                corners[static_cast<std::size_t>(sideBit | (1 << a) | (1 << b))],
                corners[static_cast<std::size_t>(sideBit | (1 << b))]};
        for (int face = 0; face < storage::kCubeFaceCount; ++face) {
            const int axis = face / 2;
            const float towardsViewer = (face % 2) ? worldNormal[axis] : -worldNormal[axis];
            if (towardsViewer > 0.0f)
                rasterizeBoxFace(face, faceCorners, center[axis], color);
        }
    }
}

void CubeBaker::rasterizeBoxFace(
        int face, const std::array<glm::vec3, 4>& corners, float depth, const glm::vec4& color) {
    const int axis = face / 2;
    const int u = faceAxisU(axis);
    const int v = faceAxisV(axis);
    const float res = static_cast<float>(mResolution);
    const float scaleU = res / std::max(mCellMax[u] - mCellMin[u], 1e-30f);
    const float scaleV = res / std::max(mCellMax[v] - mCellMin[v], 1e-30f);
    std::array<glm::vec2, 4> q;
    for (std::size_t i = 0; i < 4; ++i)
        q[i] = {(corners[i][u] - mCellMin[u]) * scaleU - 0.5f, (corners[i][v] - mCellMin[v]) * scaleV - 0.5f};
    float minX = q[0].x, maxX = q[0].x, minY = q[0].y, maxY = q[0].y;
    for (const glm::vec2& p : q) {
        minX = std::min(minX, p.x);
        maxX = std::max(maxX, p.x);
        minY = std::min(minY, p.y);
        maxY = std::max(maxY, p.y);
    }
    const int i0 = std::max(0, static_cast<int>(std::ceil(minX)));
    const int i1 = std::min(mResolution - 1, static_cast<int>(std::floor(maxX)));
    const int j0 = std::max(0, static_cast<int>(std::ceil(minY)));
    const int j1 = std::min(mResolution - 1, static_cast<int>(std::floor(maxY)));
    // A box face smaller than the sample spacing still contributes: spread it as partial
    // coverage over its nearest sample instead of dropping it between samples.
    if (i0 > i1 || j0 > j1) {
        const int i = std::clamp(static_cast<int>(std::lround(0.5f * (minX + maxX))), 0, mResolution - 1);
        const int j = std::clamp(static_cast<int>(std::lround(0.5f * (minY + maxY))), 0, mResolution - 1);
        const float centerX = 0.5f * (minX + maxX);
        const float centerY = 0.5f * (minY + maxY);
        if (centerX < -0.5f || centerX > res - 0.5f || centerY < -0.5f || centerY > res - 0.5f)
            return;
        float footprint = 0.0f; // projected area in sample units (shoelace)
        for (std::size_t k = 0; k < 4; ++k) {
            const glm::vec2& a = q[k];
            const glm::vec2& b = q[(k + 1) % 4];
            footprint += a.x * b.y - b.x * a.y;
        }
        footprint = std::min(std::fabs(0.5f * footprint), 1.0f);
        mBoxFragments[static_cast<std::size_t>(face)].push_back({depth, color * footprint, j * mResolution + i});
        return;
    }
    for (int j = j0; j <= j1; ++j) {
        for (int i = i0; i <= i1; ++i) {
            const glm::vec2 s(static_cast<float>(i), static_cast<float>(j));
            // Inside a convex quad: same side of all four edges.
            bool positive = true;
            bool negative = true;
            for (std::size_t k = 0; k < 4; ++k) {
                const glm::vec2& a = q[k];
                const glm::vec2& b = q[(k + 1) % 4];
                const float e = (b.x - a.x) * (s.y - a.y) - (b.y - a.y) * (s.x - a.x);
                positive = positive && e >= -1e-6f;
                negative = negative && e <= 1e-6f;
            }
            if (positive || negative)
                mBoxFragments[static_cast<std::size_t>(face)].push_back({depth, color, j * mResolution + i});
        }
    }
}

int CubeBaker::coveredSamples(int face) const {
    const AxisGrid& grid = mGrids[static_cast<std::size_t>(face / 2)];
    const auto& depths = (face % 2) ? grid.maxDepth : grid.minDepth;
    return static_cast<int>(std::count_if(depths.begin(), depths.end(), [](float d) { return std::isfinite(d); }));
}

ColorCube CubeBaker::finish(const QuadrantColors* underlay) {
    ColorCube cube;
    const auto samples = static_cast<std::size_t>(mResolution * mResolution);
    std::vector<glm::vec4> boxColor;
    for (int face = 0; face < storage::kCubeFaceCount; ++face) {
        const std::size_t f = static_cast<std::size_t>(face);
        const AxisGrid& grid = mGrids[f / 2];
        const bool plusSide = face % 2 == 1;

        // Boxes front to back per sample: the viewer of a + face sees large coordinates first.
        auto& fragments = mBoxFragments[f];
        std::sort(fragments.begin(), fragments.end(), [plusSide](const Fragment& a, const Fragment& b) {
            if (a.sample != b.sample)
                return a.sample < b.sample;
            return plusSide ? a.depth > b.depth : a.depth < b.depth;
        });
        boxColor.assign(samples, glm::vec4(0.0f));
        for (const Fragment& fragment : fragments) {
            glm::vec4& accumulated = boxColor[static_cast<std::size_t>(fragment.sample)];
            accumulated = over(accumulated, fragment.color); // accumulated is in front
        }

        glm::vec4 sum(0.0f);
        for (int j = 0; j < mResolution; ++j) {
            for (int i = 0; i < mResolution; ++i) {
                const auto s = static_cast<std::size_t>(j * mResolution + i);
                const float depth = plusSide ? grid.maxDepth[s] : grid.minDepth[s];
                if (std::isfinite(depth)) {
                    sum += glm::vec4(plusSide ? grid.maxColor[s] : grid.minColor[s], 1.0f);
                    continue;
                }
                glm::vec4 color = boxColor[s];
                if (underlay)
                    color = over(color, underlayColor((*underlay)[f], i, j, mResolution));
                sum += color;
            }
        }
        cube.faces[f] = sum / static_cast<float>(samples);
    }
    return cube;
}

} // namespace ff::builder
