#include "FarfieldProcess.h"

#include "ImageOutput.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>

extern char** environ;

namespace ff::viewer::test {

namespace fs = std::filesystem;

namespace {

std::string readText(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

} // namespace

std::string ProcessResult::describe() const {
    std::ostringstream text;
    text << command << ": ";
    if (exited)
        text << "exit " << exitCode;
    else if (signaled)
        text << "killed by signal " << signal << " (" << strsignal(signal) << ")";
    else
        text << "did not run";
    text << "\nstdout: " << out.substr(0, 2000) << "\nstderr: " << err.substr(0, 2000);
    return text.str();
}

ProcessResult runFarfield(const std::vector<std::string>& args, const fs::path& scratch) {
    ProcessResult result;
    result.command = "farfield";
    for (const std::string& a : args)
        result.command += " " + a;

    // One pair of capture files per call, numbered so earlier ones stay for a post-mortem.
    // Not thread-safe; the tests spawn from the main thread only.
    static int sCall = 0;
    const std::string stem = "process" + std::to_string(sCall++);
    const fs::path outPath = scratch / (stem + ".out");
    const fs::path errPath = scratch / (stem + ".err");

    std::vector<std::string> storage;
    storage.reserve(args.size() + 1);
    storage.emplace_back(FF_FARFIELD_EXE);
    storage.insert(storage.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (std::string& s : storage)
        argv.push_back(s.data());
    argv.push_back(nullptr);

    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_addopen(
            &actions, 1, outPath.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_addopen(
            &actions, 2, errPath.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);

    const auto start = std::chrono::steady_clock::now();
    pid_t pid = 0;
    const int spawned = posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    if (spawned != 0) {
        ADD_FAILURE() << "cannot spawn " << argv[0] << ": " << std::strerror(spawned);
        return result;
    }
    int status = 0;
    rusage usage{};
    pid_t waited = -1;
    do {
        waited = wait4(pid, &status, 0, &usage);
    } while (waited < 0 && errno == EINTR);
    result.seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (waited != pid) {
        ADD_FAILURE() << "wait4 failed: " << std::strerror(errno);
        return result;
    }
    result.exited = WIFEXITED(status);
    result.exitCode = result.exited ? WEXITSTATUS(status) : -1;
    result.signaled = WIFSIGNALED(status);
    result.signal = result.signaled ? WTERMSIG(status) : 0;
    result.maxRssBytes = static_cast<std::uint64_t>(usage.ru_maxrss) * 1024u; // Linux: KiB
    result.out = readText(outPath);
    result.err = readText(errPath);
    return result;
}

fs::path freshTestDir() {
    const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = std::string(info->test_suite_name()) + "." + info->name();
    for (char& c : name) {
        if (c == '/')
            c = '_';
    }
    const fs::path dir = fs::path(FF_TEST_TMP_DIR) / name;
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir;
}

nlohmann::json readJsonFile(const fs::path& path) {
    return nlohmann::json::parse(readText(path), nullptr, false);
}

runtime::Image decodeImage(const fs::path& path) {
    auto image = readImage(path);
    if (!image) {
        ADD_FAILURE() << image.status().toString();
        return {};
    }
    return std::move(image).value();
}

runtime::Image renderToImage(
        const fs::path& scene, const fs::path& png, const std::vector<std::string>& args, const fs::path& scratch) {
    std::vector<std::string> command = {"render", scene.string(), "-o", png.string()};
    command.insert(command.end(), args.begin(), args.end());
    const ProcessResult rendered = runFarfield(command, scratch);
    if (!rendered.exited || rendered.exitCode != 0) {
        ADD_FAILURE() << rendered.describe();
        return {};
    }
    return decodeImage(png);
}

std::uint64_t coveredPixels(const runtime::Image& image) {
    std::uint64_t covered = 0;
    for (std::size_t i = 3; i < image.rgba.size(); i += 4)
        covered += image.rgba[i] > 0 ? 1u : 0u;
    return covered;
}

std::uint64_t differingPixels(const runtime::Image& a, const runtime::Image& b) {
    if (a.width != b.width || a.height != b.height || a.rgba.size() != b.rgba.size())
        return static_cast<std::uint64_t>(std::max(a.rgba.size(), b.rgba.size()) / 4);
    std::uint64_t differing = 0;
    for (std::size_t p = 0; p < a.rgba.size(); p += 4)
        differing += std::memcmp(&a.rgba[p], &b.rgba[p], 4) != 0 ? 1u : 0u;
    return differing;
}

std::vector<unsigned char> readBytes(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void writeBytes(const fs::path& path, const std::vector<unsigned char>& bytes) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(
            reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
}

} // namespace ff::viewer::test
