#pragma once

// The one way builder sources include tinygltf's declarations. tiny_gltf.h (Debian 2.7.0) is not
// clean under our warning set (-Wconversion, -Wsign-conversion, -Wshadow, ...), so its warnings
// are silenced around the include only; our own code stays fully checked.

#if defined(__GNUC__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wall"
#pragma GCC diagnostic ignored "-Wextra"
#pragma GCC diagnostic ignored "-Wpedantic"
#pragma GCC diagnostic ignored "-Wshadow"
#pragma GCC diagnostic ignored "-Wconversion"
#pragma GCC diagnostic ignored "-Wsign-conversion"
#endif
#include <tiny_gltf.h>
#if defined(__GNUC__)
#pragma GCC diagnostic pop
#endif
