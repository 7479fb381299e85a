#!/usr/bin/env bash
# The whole test suite: install, build with warnings as errors under AddressSanitizer and
# UndefinedBehaviorSanitizer and run every test; then build the threaded modules under
# ThreadSanitizer and run their tests (and the runtime's decode stage).
set -euo pipefail
cd "$(dirname "$0")/.."

bash scripts/install-deps.sh
jobs=$(nproc)

cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=Debug -DFF_WERROR=ON -DFF_SANITIZE=address,undefined
cmake --build build-asan -j "$jobs"
# LLVM inside llvmpipe keeps allocations for the life of the process; they are not ours.
export LSAN_OPTIONS="suppressions=$PWD/scripts/lsan.supp:print_suppressions=0"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
# Memory bounds are a property of the product binary, not of ASan's allocator (which adds
# hundreds of MB of quarantine and shadow): they are measured on the plain build below. The
# builder's budget, and a frame's transient memory on a cut of 16.8 M cubes.
memory_test='BuildCommandTest.TerrainEightTimesTheBudgetBuildsWithinIt|SyntheticCutTest.ACutOfSeventeenMillionCubesTakesUnder64MiB'
# Inputs at full size, minutes under a sanitizer: the plain build runs them (smaller variants of
# the same cases run under the sanitizers).
large_test='DecompositionBuildTest.DegenerateAMillionIdenticalTriangles'
ctest --test-dir build-asan --output-on-failure -j "$jobs" -LE gpu -E "$memory_test|$large_test"
# Suites that render (label gpu) start OSMesa/llvmpipe, whose rasteriser threads make
# LeakSanitizer's tracer crash now and then ("Tracer caught signal 11"): leak detection is off
# for them; address and undefined-behaviour checks stay on.
ASAN_OPTIONS=detect_leaks=0 ctest --test-dir build-asan --output-on-failure -j "$jobs" -L gpu -E "$memory_test"

cmake -S . -B build-plain -G Ninja -DCMAKE_BUILD_TYPE=Debug -DFF_WERROR=ON
cmake --build build-plain -j "$jobs" --target ff_viewer_tests ff_runtime_tests ff_builder_tests farfield ff_oiio
ctest --test-dir build-plain --output-on-failure -R "$memory_test|$large_test"

cmake -S . -B build-tsan -G Ninja -DCMAKE_BUILD_TYPE=Debug -DFF_WERROR=ON -DFF_SANITIZE=thread
cmake --build build-tsan -j "$jobs" --target ff_builder_tests ff_storage_tests ff_cache_tests ff_runtime_tests
# Measuring stand-ins draws every candidate and its source on a CPU raster, a minute of TSan's
# instrumented loops for this one test; its threads are SceneV2Test.SameInputGivesTheSameBytes…'s,
# which TSan runs.
tsan_slow='SceneV2Test.MeasuredChoiceKeepsOnlyTheStandInsThatKeepTheirShape'
ctest --test-dir build-tsan --output-on-failure -j "$jobs" -L "builder|storage|cache" -E "$large_test|$tsan_slow"
# The runtime's own threads: format 2's decode stage between the cache and the GPU arena.
ctest --test-dir build-tsan --output-on-failure -j "$jobs" -R "CachedClusterPageTest"
