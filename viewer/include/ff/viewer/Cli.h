#pragma once

namespace ff::viewer {

/**
 * The `farfield` command line: parses argv and runs one verb (build, render, view, check, bench).
 * Returns the process exit code: 0 success, 1 a failure the message explains, 2 bad usage.
 */
int runCli(int argc, char** argv);

} // namespace ff::viewer
