#include "Shaders.h"

// The shading model here must match storage/ShadingModel.h (the builder bakes cubes with it).

namespace ff::runtime::gl {

const char* const kCubeShaderInputs = R"(#version 450 core
layout(location = 0) in vec3 aBoxMin;
layout(location = 1) in vec3 aBoxMax;
layout(location = 2) in uint aTransform;
layout(location = 3) in vec4 aFaces[6];    // premultiplied linear RGBA8, -X +X -Y +Y -Z +Z
layout(std430, binding = 0) readonly buffer Transforms { mat4 transforms[]; };
layout(std430, binding = 2) readonly buffer LocalEyes { vec4 localEyes[]; };
uniform mat4 uViewProjection;
flat out uint vCube; // which cube of the batch (kVisibleCubeFragmentShader)
)";

const char* const kGeometryVertexShader = R"(#version 450 core
layout(location = 0) in vec3 aPosition;
layout(location = 1) in ivec2 aNormalOct;  // snorm16, octahedral; (-32768, -32768): unlit
layout(location = 2) in vec4 aColor;       // sRGB8 rgb, linear alpha
layout(location = 3) in uint aTransform;   // per draw, from baseInstance
layout(location = 4) in float aPointSize;  // splats only: their diameter in output pixels
layout(std430, binding = 0) readonly buffer Transforms { mat4 transforms[]; };
layout(std430, binding = 1) readonly buffer NormalMatrices { mat4 normalMatrices[]; };
uniform mat4 uViewProjection;
uniform vec3 uLightDirection;
uniform float uAmbient;
uniform float uDiffuse;
uniform float uPointScale; // render-target pixels an output pixel spans (supersampling)
out vec3 vColor;

vec3 decodeOct(vec2 e) {
    vec3 v = vec3(e, 1.0 - abs(e.x) - abs(e.y));
    if (v.z < 0.0)
        v.xy = (1.0 - abs(v.yx)) * vec2(v.x >= 0.0 ? 1.0 : -1.0, v.y >= 0.0 ? 1.0 : -1.0);
    return normalize(v);
}

vec3 srgbToLinear(vec3 c) {
    return mix(c / 12.92, pow((c + 0.055) / 1.055, vec3(2.4)), greaterThan(c, vec3(0.04045)));
}

void main() {
    mat4 model = transforms[aTransform];
    gl_Position = uViewProjection * (model * vec4(aPosition, 1.0));
    // storage::kUnlitNormalOct marks KHR_materials_unlit: the colour as it is (kUnlitShading).
    float light = 1.0;
    if (aNormalOct != ivec2(-32768)) {
        vec3 n = normalize(mat3(normalMatrices[aTransform]) * decodeOct(max(vec2(aNormalOct) / 32767.0, vec2(-1.0))));
        light = uAmbient + uDiffuse * abs(dot(n, uLightDirection));
    }
    vColor = srgbToLinear(aColor.rgb) * light;
    gl_PointSize = aPointSize * uPointScale;
}
)";

const char* const kGeometryFragmentShader = R"(#version 450 core
in vec3 vColor;
layout(location = 0) out vec4 fragColor;
void main() { fragColor = vec4(vColor, 1.0); }
)";

// A program apart: a discard in the triangles' shader would cost them early depth testing.
const char* const kRoundSplatFragmentShader = R"(#version 450 core
in vec3 vColor;
layout(location = 0) out vec4 fragColor;
void main() {
    vec2 d = gl_PointCoord - vec2(0.5);
    if (dot(d, d) > 0.25)
        discard;
    fragColor = vec4(vColor, 1.0);
}
)";

const char* const kCubeVertexShader = R"(out vec4 vColor;

const ivec2 kCorners[6] = ivec2[6](ivec2(0, 0), ivec2(1, 0), ivec2(1, 1), ivec2(0, 0), ivec2(1, 1), ivec2(0, 1));

// 18 vertices per cube: a box shows at most one face per axis, the one on the eye's side, and
// none on an axis whose slab holds the eye.
void main() {
    vCube = uint(gl_InstanceID);
    int axis = gl_VertexID / 6;
    int u = (axis + 1) % 3;
    int v = (axis + 2) % 3;
    vec3 eye = localEyes[aTransform].xyz;
    bool plusSide = eye[axis] > aBoxMax[axis];
    bool facesViewer = plusSide || eye[axis] < aBoxMin[axis];
    vColor = aFaces[2 * axis + (plusSide ? 1 : 0)];
    if (!facesViewer || vColor.a <= 0.0) {
        gl_Position = vec4(2.0, 2.0, 2.0, 1.0); // outside the clip volume: the face vanishes
        return;
    }
    ivec2 corner = kCorners[gl_VertexID % 6];
    vec3 p;
    p[axis] = plusSide ? aBoxMax[axis] : aBoxMin[axis];
    p[u] = corner.x == 1 ? aBoxMax[u] : aBoxMin[u];
    p[v] = corner.y == 1 ? aBoxMax[v] : aBoxMin[v];
    gl_Position = uViewProjection * (transforms[aTransform] * vec4(p, 1.0));
}
)";

const char* const kCubePointVertexShader = R"(uniform float uPixelScale; // pixels per world unit at view depth 1 (orthographic: per unit)
out vec4 vColor;

// A cube smaller than a pixel or two, drawn as one point: the faces the viewer sees, weighted by
// their projected areas (a box face's area times |cos| to the view direction), with alpha scaled
// by how much of the point the box really covers, so coverage stays right on average instead of
// depending on which pixel centres a tiny quad happens to hit.
void main() {
    vCube = uint(gl_InstanceID);
    vec3 center = 0.5 * (aBoxMin + aBoxMax);
    vec3 extent = aBoxMax - aBoxMin;
    vec3 toEye = localEyes[aTransform].xyz - center;
    vec3 direction = toEye / max(length(toEye), 1e-30);
    vec3 weight = vec3(extent.y * extent.z, extent.z * extent.x, extent.x * extent.y) * abs(direction);
    float area = weight.x + weight.y + weight.z; // the box's projected area, local units
    vec4 color = weight.x * aFaces[direction.x > 0.0 ? 1 : 0] + weight.y * aFaces[direction.y > 0.0 ? 3 : 2] +
                 weight.z * aFaces[direction.z > 0.0 ? 5 : 4];
    color /= max(area, 1e-30);
    mat4 model = transforms[aTransform];
    gl_Position = uViewProjection * (model * vec4(center, 1.0));
    // The projected area in world units through the whole linear part M (axes scaled apart,
    // mirrored, sheared): a face's area vector a maps to det(M) M^-T a, whose component along the
    // world direction M t / |M t| is |det M| |a . t| / |M t| (TransformMetric::projectedArea).
    mat3 linear = mat3(model);
    float worldArea = abs(determinant(linear)) * area * length(toEye) / max(length(linear * toEye), 1e-30);
    float scale = uPixelScale / max(gl_Position.w, 1e-30);
    float pixels = worldArea * scale * scale;
    float size = max(1.0, ceil(sqrt(pixels)));
    gl_PointSize = size;
    vColor = color * min(1.0, pixels / (size * size));
}
)";

const char* const kCubeFragmentShader = R"(#version 450 core
in vec4 vColor;
layout(location = 0) out vec4 fragColor;
void main() { fragColor = vColor; }
)";

const char* const kCubeOccluderFragmentShader = R"(#version 450 core
in vec4 vColor;
// Per sample, layer 0: the opacity composited so far, as -log2(transmittance) in 1/65536ths, a
// sum, so fragments add to it in any order (atomically) and the total is the same. Layer 1: the
// farthest depth among the fragments in that sum (as bits: depths are non-negative floats).
layout(r32ui, binding = 0) uniform coherent uimage2DArray uOpacity;
uniform uint uOccludes;   // the sum at which a sample's transmittance reaches the threshold
uniform float uDepthBias; // the depth written lies this far behind the face (see below)
void main() {
    ivec3 sum = ivec3(gl_FragCoord.xy, 0);
    ivec3 farthest = ivec3(gl_FragCoord.xy, 1);
    float depth = gl_FragCoord.z;
    float alpha = vColor.a;
    if (alpha < 1.0 - 0.5 / 255.0) {
        // Translucent: the sample occludes once the sum reaches the threshold, but only behind
        // every fragment that made it up. The walk meets cubes front to back by node, not by
        // sample, so the fragment that crosses the threshold may lie in front of the others.
        uint add = uint(min(-log2(1.0 - alpha) * 65536.0, float(uOccludes)));
        if (add == 0u || imageLoad(uOpacity, sum).x >= uOccludes)
            discard; // adds nothing, or the sample already occludes (its depth is written)
        imageAtomicMax(uOpacity, farthest, floatBitsToUint(depth));
        memoryBarrierImage(); // whoever sees this fragment's share in the sum sees its depth
        if (imageAtomicAdd(uOpacity, sum, add) + add < uOccludes)
            discard; // light still shows through: no depth
        memoryBarrierImage();
        depth = max(depth, uintBitsToFloat(imageLoad(uOpacity, farthest).x));
    }
    // An opaque face hides what lies behind it whatever came before. A hair behind, so the color
    // pass's own fragment still passes GL_LESS (points have no polygon offset).
    gl_FragDepth = min(depth + uDepthBias, 1.0);
}
)";

// The oracle's pass (Renderer::visibleParts): a fragment that passes the depth test sets its
// triangle's or cube's bit. The test runs before the shader (early_fragment_tests), or every
// fragment would set its bit.
const char* const kVisibleTriangleFragmentShader = R"(#version 450 core
layout(early_fragment_tests) in;
layout(std430, binding = 3) buffer Visible { uint visibleBits[]; };
uniform uint uFirstBit; // the draw's first triangle's bit
void main() {
    uint bit = uFirstBit + uint(gl_PrimitiveID);
    atomicOr(visibleBits[bit >> 5], 1u << (bit & 31u));
}
)";

const char* const kVisibleCubeFragmentShader = R"(#version 450 core
layout(early_fragment_tests) in;
in vec4 vColor;
flat in uint vCube;
layout(std430, binding = 3) buffer Visible { uint visibleBits[]; };
uniform uint uFirstBit; // the batch's first cube's bit
void main() {
    if (vColor.a <= 0.0)
        return; // adds nothing to the image
    uint bit = uFirstBit + vCube;
    atomicOr(visibleBits[bit >> 5], 1u << (bit & 31u));
}
)";

} // namespace ff::runtime::gl
