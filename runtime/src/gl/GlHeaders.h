#pragma once

// GL entry points come straight from the OSMesa library (DESIGN.md: define GL_GLEXT_PROTOTYPES
// before the first GL include).
#ifndef GL_GLEXT_PROTOTYPES
#define GL_GLEXT_PROTOTYPES 1
#endif
#include <GL/gl.h>
#include <GL/glext.h>
