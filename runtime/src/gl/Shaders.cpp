#include "Shaders.h"

// The shading model here must match storage/ShadingModel.h (the builder bakes cubes with it).

namespace ff::runtime::gl {

const char* const kGeometryVertexShader = R"(#version 450 core
layout(location = 0) in vec3 aPosition;
layout(location = 1) in vec2 aNormalOct;   // snorm16, octahedral
layout(location = 2) in vec4 aColor;       // sRGB8 rgb, linear alpha
layout(location = 3) in uint aTransform;   // per draw, from baseInstance
layout(std430, binding = 0) readonly buffer Transforms { mat4 transforms[]; };
layout(std430, binding = 1) readonly buffer NormalMatrices { mat4 normalMatrices[]; };
uniform mat4 uViewProjection;
uniform vec3 uLightDirection;
uniform float uAmbient;
uniform float uDiffuse;
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
    vec3 n = normalize(mat3(normalMatrices[aTransform]) * decodeOct(max(aNormalOct, vec2(-1.0))));
    float light = uAmbient + uDiffuse * abs(dot(n, uLightDirection));
    vColor = srgbToLinear(aColor.rgb) * light;
}
)";

const char* const kGeometryFragmentShader = R"(#version 450 core
in vec3 vColor;
layout(location = 0) out vec4 fragColor;
void main() { fragColor = vec4(vColor, 1.0); }
)";

const char* const kCubeVertexShader = R"(#version 450 core
layout(location = 0) in vec3 aBoxMin;
layout(location = 1) in vec3 aBoxMax;
layout(location = 2) in uint aTransform;
layout(location = 3) in vec4 aFaces[6];    // premultiplied linear RGBA8, -X +X -Y +Y -Z +Z
layout(std430, binding = 0) readonly buffer Transforms { mat4 transforms[]; };
layout(std430, binding = 2) readonly buffer LocalEyes { vec4 localEyes[]; };
uniform mat4 uViewProjection;
out vec4 vColor;

const ivec2 kCorners[6] = ivec2[6](ivec2(0, 0), ivec2(1, 0), ivec2(1, 1), ivec2(0, 0), ivec2(1, 1), ivec2(0, 1));

// 18 vertices per cube: a box shows at most one face per axis, the one on the eye's side, and
// none on an axis whose slab holds the eye.
void main() {
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

const char* const kCubeFragmentShader = R"(#version 450 core
in vec4 vColor;
layout(location = 0) out vec4 fragColor;
void main() { fragColor = vColor; }
)";

} // namespace ff::runtime::gl
