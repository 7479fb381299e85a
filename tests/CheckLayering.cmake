# Dependency rules a compiler does not see (DESIGN.md, issue 14): viewer/ is the CLI and the
# window, so no source under viewer/ or bench/ names the page cache; the streaming session in
# runtime/ owns it. Run as a test: cmake -DSOURCE_DIR=<repo> -P CheckLayering.cmake
file(GLOB_RECURSE sources "${SOURCE_DIR}/viewer/*.cpp" "${SOURCE_DIR}/viewer/*.h"
                          "${SOURCE_DIR}/bench/*.cpp" "${SOURCE_DIR}/bench/*.h")
set(offenders "")
foreach(source IN LISTS sources)
    file(STRINGS "${source}" lines REGEX "ff/cache/|cache::")
    if(lines)
        list(APPEND offenders "${source}: ${lines}")
    endif()
endforeach()
if(offenders)
    list(JOIN offenders "\n" text)
    message(FATAL_ERROR "the page cache is named above runtime/:\n${text}")
endif()
list(LENGTH sources count)
message(STATUS "${count} sources under viewer/ and bench/ name no part of the page cache")
