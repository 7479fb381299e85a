#pragma once

// FF_ASSERT checks programming errors (broken preconditions), never file or network bytes:
// those are data and get a Status. On in Debug builds; define FF_FORCE_ASSERTS to keep them in
// Release.

#include <cstdio>
#include <cstdlib>

#if !defined(NDEBUG) || defined(FF_FORCE_ASSERTS)
#define FF_ASSERT(cond)                                                                            \
    do {                                                                                           \
        if (!(cond)) {                                                                             \
            std::fprintf(stderr, "%s:%d: assertion failed: %s\n", __FILE__, __LINE__, #cond);      \
            std::abort();                                                                          \
        }                                                                                          \
    } while (false)
#else
#define FF_ASSERT(cond)                                                                            \
    do {                                                                                           \
        (void)sizeof(cond);                                                                        \
    } while (false)
#endif
