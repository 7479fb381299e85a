#pragma once

// Runs the real `farfield` executable as a child process (posix_spawn, no shell) for the
// end-to-end tests, and small helpers they share: a fresh scratch directory per test, the JSON
// build report, decoded images.

#include <ff/runtime/Image.h>

#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace ff::viewer::test {

/** How a `farfield` child ended. */
struct ProcessResult {
    bool exited = false;           ///< WIFEXITED
    int exitCode = -1;             ///< WEXITSTATUS if exited
    bool signaled = false;         ///< WIFSIGNALED (a crash or abort)
    int signal = 0;                ///< WTERMSIG if signaled
    std::uint64_t maxRssBytes = 0; ///< ru_maxrss of the child (from wait4)
    double seconds = 0.0;          ///< wall time
    std::string out;               ///< captured stdout
    std::string err;               ///< captured stderr
    std::string command;           ///< the argument list, for failure messages

    /** "farfield build ...: exit 1\nstderr: ..." for assertion messages. */
    std::string describe() const;
};

/**
 * Runs FF_FARFIELD_EXE with `args` (argv[1..]), stdout and stderr captured through files in
 * `scratch`, waits for it. The child inherits the environment. Aborts the test binary only if
 * the process cannot be spawned at all.
 */
ProcessResult
runFarfield(const std::vector<std::string>& args, const std::filesystem::path& scratch);

/** An empty directory FF_TEST_TMP_DIR/<suite>.<test> for the running test (removed first). */
std::filesystem::path freshTestDir();

/** Parses a JSON file; a null json if it is missing or not JSON. */
nlohmann::json readJsonFile(const std::filesystem::path& path);

/** Decodes an image written by `farfield render` (through the viewer's OIIO plugin). */
runtime::Image decodeImage(const std::filesystem::path& path);

/** `farfield render SCENE -o PNG ARGS...` and the image it wrote. A render that fails fails the
 *  test (ADD_FAILURE) and gives an empty image. */
runtime::Image renderToImage(
        const std::filesystem::path& scene,
        const std::filesystem::path& png,
        const std::vector<std::string>& args,
        const std::filesystem::path& scratch);
/** Pixels with alpha > 0 (needs an image rendered with --coverage-alpha). */
std::uint64_t coveredPixels(const runtime::Image& image);

/** Number of pixels whose RGBA differ. Images of different sizes differ everywhere. */
std::uint64_t differingPixels(const runtime::Image& a, const runtime::Image& b);

std::vector<unsigned char> readBytes(const std::filesystem::path& path);
void writeBytes(const std::filesystem::path& path, const std::vector<unsigned char>& bytes);

} // namespace ff::viewer::test
