// `farfield view` end to end: starts its own Xvfb (GLX through Mesa's llvmpipe), runs the
// farfield binary in scripted mode and compares its screenshot with `farfield render` of the
// same view. Label `gpu`: it needs an OpenGL 4.5 core context in a window, not a GPU as such.

#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <stb_image.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <system_error>
#include <vector>

extern char** environ;

namespace {

namespace fs = std::filesystem;

// Per process: ctest runs each test in its own process, possibly in parallel.
const fs::path kTmp = fs::path(FF_TEST_TMP_DIR) / ("view-" + std::to_string(getpid()));

// Every variable of this process, with DISPLAY replaced (or removed when `display` is empty).
// Leak checking (ASan builds) is off in the children; address and UB checks stay on. GLX
// unloads Mesa's driver at glfwTerminate, so the driver's leftovers show up from "<unknown
// module>", which no suppression can name; and LeakSanitizer (GCC 12, glibc 2.36) itself
// crashes on llvmpipe's dynamic TLS in some `render` runs ("Tracer caught signal 11").
std::vector<std::string> environmentWithDisplay(const std::string& display) {
    std::vector<std::string> env;
    std::string lsan = "LSAN_OPTIONS=detect_leaks=0";
    for (char** e = environ; *e; ++e) {
        if (std::strncmp(*e, "LSAN_OPTIONS=", 13) == 0)
            lsan = std::string(*e) + ":detect_leaks=0"; // the last setting wins
        else if (std::strncmp(*e, "DISPLAY=", 8) != 0)
            env.emplace_back(*e);
    }
    env.push_back(lsan);
    if (!display.empty())
        env.push_back("DISPLAY=" + display);
    return env;
}

std::vector<char*> pointers(std::vector<std::string>& strings) {
    std::vector<char*> out;
    for (std::string& s : strings)
        out.push_back(s.data());
    out.push_back(nullptr);
    return out;
}

struct RunResult {
    int exitCode = -1;
    std::string output; // stdout and stderr together
};

// Runs argv[0] (a path) with stdout and stderr into a log, waits for it.
RunResult
run(std::vector<std::string> argv, const std::string& display, const std::string& logName) {
    const fs::path log = kTmp / logName;
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&actions, 1, 2);
    std::vector<std::string> env = environmentWithDisplay(display);
    std::vector<char*> argp = pointers(argv);
    std::vector<char*> envp = pointers(env);
    pid_t pid = 0;
    RunResult result;
    if (posix_spawn(&pid, argp[0], &actions, nullptr, argp.data(), envp.data()) == 0) {
        int status = 0;
        waitpid(pid, &status, 0);
        result.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    }
    posix_spawn_file_actions_destroy(&actions);
    std::ifstream in(log);
    std::stringstream text;
    text << in.rdbuf();
    result.output = text.str();
    return result;
}

struct Rgb {
    int width = 0;
    int height = 0;
    std::vector<unsigned char> pixels; // width * height * 3
};

Rgb loadPng(const fs::path& path) {
    Rgb image;
    int channels = 0;
    unsigned char* data = stbi_load(path.c_str(), &image.width, &image.height, &channels, 3);
    if (data) {
        image.pixels.assign(
                data,
                data + static_cast<std::size_t>(image.width) *
                                static_cast<std::size_t>(image.height) * 3);
        stbi_image_free(data);
    }
    return image;
}

// Mean absolute difference per channel, in 8-bit levels.
double meanAbsoluteDifference(const Rgb& a, const Rgb& b) {
    double sum = 0.0;
    for (std::size_t i = 0; i < a.pixels.size(); ++i)
        sum += std::abs(int(a.pixels[i]) - int(b.pixels[i]));
    return sum / static_cast<double>(a.pixels.size());
}

// Share of pixels that differ from the top-left (background) pixel by more than 8 levels.
double coveredShare(const Rgb& image) {
    std::size_t covered = 0;
    const std::size_t count = image.pixels.size() / 3;
    for (std::size_t p = 0; p < count; ++p)
        for (std::size_t c = 0; c < 3; ++c)
            if (std::abs(int(image.pixels[3 * p + c]) - int(image.pixels[c])) > 8) {
                ++covered;
                break;
            }
    return static_cast<double>(covered) / static_cast<double>(count);
}

class ViewScriptedTest : public testing::Test {
protected:
    static void SetUpTestSuite() {
        fs::create_directories(kTmp);
        sScene = (kTmp / "forest4.ffs").string();
        const RunResult build =
                run({FF_FARFIELD_EXE, "build", "--generate", "forest:trees=4", "-o", sScene, "-q"},
                    "",
                    "build.log");
        sBuildOk = build.exitCode == 0;
        sBuildLog = build.output;
        startXvfb();
    }

    static void TearDownTestSuite() {
        if (sXvfb > 0) {
            kill(sXvfb, SIGTERM);
            waitpid(sXvfb, nullptr, 0);
            sXvfb = 0;
        }
        // Images and logs stay for a look when something failed.
        if (!testing::UnitTest::GetInstance()->current_test_suite()->Failed()) {
            std::error_code error;
            fs::remove_all(kTmp, error);
        }
    }

    // Xvfb picks a free display itself and writes its number to -displayfd once it accepts
    // connections; we also wait for its socket.
    static void startXvfb() {
        int fds[2];
        if (pipe(fds) != 0)
            return;
        fcntl(fds[0], F_SETFD, FD_CLOEXEC);
        std::vector<std::string> argv = {
                "Xvfb",
                "-displayfd",
                std::to_string(fds[1]),
                "-screen",
                "0",
                "1024x768x24",
                "-nolisten",
                "tcp"};
        std::vector<char*> argp = pointers(argv);
        posix_spawn_file_actions_t actions;
        posix_spawn_file_actions_init(&actions);
        const std::string log = (kTmp / "xvfb.log").string();
        posix_spawn_file_actions_addopen(
                &actions, 2, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
        const int spawned = posix_spawnp(&sXvfb, "Xvfb", &actions, nullptr, argp.data(), environ);
        posix_spawn_file_actions_destroy(&actions);
        close(fds[1]);
        if (spawned != 0) {
            sXvfb = 0;
            close(fds[0]);
            return;
        }
        std::string number;
        pollfd p{fds[0], POLLIN, 0};
        while (poll(&p, 1, 10000) > 0) {
            char c = 0;
            if (read(fds[0], &c, 1) != 1 || c == '\n')
                break;
            number += c;
        }
        close(fds[0]);
        const fs::path socket = "/tmp/.X11-unix/X" + number;
        for (int i = 0; i < 100 && !number.empty() && !fs::exists(socket); ++i)
            usleep(100 * 1000);
        if (!number.empty() && fs::exists(socket))
            sDisplay = ":" + number;
    }

    void SetUp() override {
        ASSERT_TRUE(sBuildOk) << sBuildLog;
        if (sXvfb == 0)
            GTEST_SKIP() << "Xvfb is not installed (apt-get install xvfb)";
        ASSERT_FALSE(sDisplay.empty()) << "Xvfb did not come up; see " << (kTmp / "xvfb.log");
    }

    // Runs `view` scripted and `render` of the same view; returns (screenshot, reference).
    std::pair<Rgb, Rgb> viewAndRender(
            const std::string& name,
            const std::vector<std::string>& viewArgs,
            const std::vector<std::string>& renderArgs) {
        const std::string shot = (kTmp / (name + "-view.png")).string();
        const std::string ref = (kTmp / (name + "-render.png")).string();
        std::vector<std::string> view = {
                FF_FARFIELD_EXE, "view", sScene, "--size", "320x240", "--screenshot", shot};
        view.insert(view.end(), viewArgs.begin(), viewArgs.end());
        const RunResult viewed = run(view, sDisplay, name + "-view.log");
        EXPECT_EQ(viewed.exitCode, 0) << viewed.output;
        std::vector<std::string> render = {
                FF_FARFIELD_EXE, "render", sScene, "--size", "320x240", "-o", ref};
        render.insert(render.end(), renderArgs.begin(), renderArgs.end());
        const RunResult rendered = run(render, "", name + "-render.log");
        EXPECT_EQ(rendered.exitCode, 0) << rendered.output;
        return {loadPng(shot), loadPng(ref)};
    }

    static inline pid_t sXvfb = 0;
    static inline std::string sDisplay;
    static inline std::string sScene;
    static inline bool sBuildOk = false;
    static inline std::string sBuildLog;
};

// Tolerance, mean absolute difference per channel in 8-bit levels: the window composites
// cubes over the background on the GPU (8-bit sRGB blending) where render() composites on the
// CPU in float, and a scripted orbit rebuilds the camera from angles, so a few cube and edge
// pixels differ by a level. Measured (Mesa 22.3 llvmpipe, 320x240): 0.0001 for the orbit view,
// 0.03 for the cube-heavy view; the same orbit view one degree off scores 1.8. Hence 0.25.
constexpr double kMaxMeanDifference = 0.25;

TEST_F(ViewScriptedTest, ScreenshotOfAnOrbitScriptMatchesRenderOfTheSameView) {
    // Five frames, 5 degrees of orbit after each of the first four: azimuth 30 + 20.
    const auto [shot, reference] =
            viewAndRender("orbit", {"--frames", "5", "--script", "orbit:5"}, {"--azimuth", "50"});
    ASSERT_EQ(shot.width, 320);
    ASSERT_EQ(shot.height, 240);
    ASSERT_EQ(reference.width, 320);
    ASSERT_EQ(reference.height, 240);
    EXPECT_GT(coveredShare(shot), 0.03) << "the screenshot is (nearly) all background";
    const double difference = meanAbsoluteDifference(shot, reference);
    RecordProperty("mean_abs_difference", std::to_string(difference));
    EXPECT_LT(difference, kMaxMeanDifference);
}

TEST_F(ViewScriptedTest, ColorCubesBlendOverTheBackgroundAsInRender) {
    // ε = 8 px: most of each tree is drawn as translucent color cubes.
    const auto [shot, reference] = viewAndRender(
            "cubes",
            {"--frames", "2", "--epsilon", "8", "--distance", "2"},
            {"--epsilon", "8", "--distance", "2"});
    ASSERT_EQ(shot.width, 320);
    ASSERT_EQ(shot.height, 240);
    EXPECT_GT(coveredShare(shot), 0.03);
    const double difference = meanAbsoluteDifference(shot, reference);
    RecordProperty("mean_abs_difference", std::to_string(difference));
    EXPECT_LT(difference, kMaxMeanDifference);
}

TEST_F(ViewScriptedTest, WithoutADisplayItExitsOneWithAMessage) {
    const RunResult result =
            run({FF_FARFIELD_EXE, "view", sScene, "--frames", "1"}, "", "nodisplay.log");
    EXPECT_EQ(result.exitCode, 1);
    EXPECT_NE(result.output.find("DISPLAY"), std::string::npos) << result.output;
}

} // namespace
