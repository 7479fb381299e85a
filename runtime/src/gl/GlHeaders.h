#pragma once

// GL entry points come through glad (generated at build time from Debian's python3-glad and
// its bundled Khronos registry), loaded from whatever context is current: OSMesa's
// OSMesaGetProcAddress headless, glfwGetProcAddress in a window. Nothing links libGL or
// libOSMesa directly, so a process that never renders (`farfield build`) never loads them.
#include <glad/gl.h>
