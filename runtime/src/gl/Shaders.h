#pragma once

namespace ff::runtime::gl {

/** Geometry: PackedVertex attributes, per-draw transform index via baseInstance. */
extern const char* const kGeometryVertexShader;
extern const char* const kGeometryFragmentShader;
/** Splats (point clusters) drawn as discs: with the geometry vertex shader, whose points are
 *  uPointSize pixels wide (squares: kGeometryFragmentShader). */
extern const char* const kRoundSplatFragmentShader;
/** Declarations both cube vertex shaders start with (#version, the per-cube attributes and
 *  buffers): compiled as the first source string before either body below. */
extern const char* const kCubeShaderInputs;
/** Color cubes: one instance per cube, 18 vertices (a face per axis), hidden faces collapsed. */
extern const char* const kCubeVertexShader;
extern const char* const kCubeFragmentShader;
/** Small color cubes: one point per cube, faces blended by projected area. */
extern const char* const kCubePointVertexShader;
/** Either cube vertex shader's fragments as occluders: depth only, where the opacity
 *  accumulated over the sample (an r32ui image) reaches the frame's threshold. */
extern const char* const kCubeOccluderFragmentShader;
/** The oracle's: with the geometry vertex shader, sets a bit per triangle that shows (the
 *  depth test at ==); with either cube vertex shader, a bit per cube that shows (at <). */
extern const char* const kVisibleTriangleFragmentShader;
extern const char* const kVisibleCubeFragmentShader;

} // namespace ff::runtime::gl
