#include "CameraController.h"
#include "CameraFlags.h"
#include "Commands.h"
#include "FrameFlags.h"
#include "Hud.h"
#include "OutputFile.h"
#include "ViewerControls.h"
#include "Window.h"

#include <ff/runtime/StreamingSession.h>
#include <ff/runtime/Units.h>
#include <ff/storage/SceneFile.h>

#include <nlohmann/json.hpp>

#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>

namespace ff::viewer {

namespace {

struct ViewArgs {
    std::string scene;
    std::string size = "1280x720";
    float epsilon = 1.0f;
    runtime::Representation representation = runtime::Representation::Auto;
    runtime::SplatStyle splats;
    std::string method = "hierarchical";
    std::string gpuBudget = "512MiB";
    std::uint64_t cacheMb = 0;
    std::size_t uploadsPerFrame = 64;
    std::uint32_t gpuUploadsPerFrame = 0;
    runtime::OcclusionOptions occlusion;
    std::string background = "0.70,0.75,0.83";
    int frames = 0;
    std::string screenshot;
    std::string screenshotDir = ".";
    CLI::Option* screenshotDirOption = nullptr; ///< given: the folder is checked at start
    std::string script;
    bool noHud = false;
    bool noVsync = false;
    runtime::CameraOptions camera;
};

/** Camera motion applied before every frame after the first (--script). */
struct ScriptStep {
    float orbitDegrees = 0.0f;   ///< azimuth about +Y
    float elevateDegrees = 0.0f; ///< elevation
    float zoomFactor = 1.0f;     ///< distance to the pivot multiplied by this
};

/** "orbit:5,elevate:1,zoom:0.98" -> a step; "" -> no motion. */
Result<ScriptStep> parseScript(std::string_view text) {
    ScriptStep step;
    while (!text.empty()) {
        const std::size_t comma = text.find(',');
        const std::string_view item = text.substr(0, comma);
        text = comma == std::string_view::npos ? std::string_view() : text.substr(comma + 1);
        const std::size_t colon = item.find(':');
        const std::string_view name = item.substr(0, colon);
        const std::string_view number =
                colon == std::string_view::npos ? std::string_view() : item.substr(colon + 1);
        float value = 0.0f;
        const auto [end, error] =
                std::from_chars(number.data(), number.data() + number.size(), value);
        if (number.empty() || error != std::errc() || end != number.data() + number.size() ||
            !std::isfinite(value))
            return Status(
                    ErrorCode::InvalidArgument,
                    "--script: expected NAME:NUMBER, got '" + std::string(item) + "'");
        if (name == "orbit")
            step.orbitDegrees = value;
        else if (name == "elevate")
            step.elevateDegrees = value;
        else if (name == "zoom" && value > 0.0f)
            step.zoomFactor = value;
        else
            return Status(
                    ErrorCode::InvalidArgument,
                    "--script: unknown step '" + std::string(item) +
                            "' (orbit:DEG, elevate:DEG, zoom:FACTOR > 0)");
    }
    return step;
}

/** The point the initial view orbits about: --target if given, else the scene centre's depth
 *  straight ahead (the centre itself for the default orbit camera). */
glm::vec3 initialPivot(
        const runtime::Camera& camera, const runtime::Bounds& bounds, const glm::dvec3& origin, const ViewArgs& args) {
    if (!args.camera.target.empty() && args.camera.camera.empty()) {
        if (auto target = runtime::parseDVec3(args.camera.target))
            return glm::vec3(*target - origin);
    }
    const float depth = glm::dot(bounds.center() - camera.eye, camera.forward);
    return camera.eye +
           camera.forward *
                   (depth > 1e-3f * bounds.radius() ? depth : std::max(bounds.radius(), 1e-3f));
}

/** screenshot-0001.png, -0002, ...: the first name not taken in `dir`. */
std::filesystem::path nextScreenshotPath(const std::filesystem::path& dir) {
    for (int n = 1;; ++n) {
        char name[32];
        std::snprintf(name, sizeof(name), "screenshot-%04d.png", n);
        std::error_code error;
        if (!std::filesystem::exists(dir / name, error))
            return dir / name;
    }
}

int runView(const ViewArgs& args) {
    // ---- Arguments --------------------------------------------------------------------------
    auto size = runtime::parseImageSize(args.size);
    if (!size)
        return reportError("view", size.status().withContext("--size"));
    const std::optional<runtime::Method> method = runtime::parseMethod(args.method);
    if (!method)
        return reportError(
                "view",
                Status(ErrorCode::InvalidArgument, "--method must be hierarchical or full"));
    if (!(args.epsilon >= 0.0f))
        return reportError("view", Status(ErrorCode::InvalidArgument, "--epsilon must be >= 0"));
    if (args.frames < 0)
        return reportError("view", Status(ErrorCode::InvalidArgument, "--frames must be >= 0"));
    auto background = runtime::parseVec3(args.background);
    if (!background)
        return reportError("view", background.status().withContext("--background"));
    auto gpuBudget = runtime::parseByteSize(args.gpuBudget);
    if (!gpuBudget)
        return reportError("view", gpuBudget.status().withContext("--gpu-budget"));
    auto script = parseScript(args.script);
    if (!script)
        return reportError("view", script.status());
    // Scripted: a fixed number of frames, no human (tests, CI). --screenshot alone means one.
    const int frames = args.frames == 0 && !args.screenshot.empty() ? 1 : args.frames;
    const bool scripted = frames > 0;
    if (!args.script.empty() && !scripted)
        return reportError("view", Status(ErrorCode::InvalidArgument, "--script needs --frames"));

    // Outputs first: an unwritable screenshot path fails before the window opens.
    auto scriptedScreenshot = reserveIfNamed(args.screenshot, OutputKind::Image);
    if (!scriptedScreenshot)
        return reportError("view", scriptedScreenshot.status().withContext("--screenshot"));
    // A folder asked for is made and checked now; the default (the current folder) only when a
    // screenshot is taken, so that view still starts from a folder it cannot write.
    if (args.screenshotDirOption != nullptr && args.screenshotDirOption->count() > 0) {
        if (const Status folder = prepareOutputFolder(args.screenshotDir); !folder)
            return reportError("view", folder.withContext("--screenshot-dir"));
    }

    // The scene is opened before the window, so that a bad file says so without a display.
    auto scene = storage::SceneFile::open(args.scene);
    if (!scene)
        return reportError("view", scene.status().withContext(args.scene));
    auto initialCamera = args.camera.resolve(**scene);
    if (!initialCamera)
        return reportError("view", initialCamera.status());
    const runtime::Bounds bounds = runtime::sceneBounds(**scene);
    const glm::dvec3 origin = runtime::sceneOrigin(**scene);
    scene->reset(); // the session opens its own

    // ---- Window, HUD, renderer (destroyed in reverse order, while the context lives) -------
    WindowOptions windowOptions;
    windowOptions.width = size->x;
    windowOptions.height = size->y;
    windowOptions.title =
            "farfield view - " + std::filesystem::path(args.scene).filename().string();
    windowOptions.resizable = !scripted;
    windowOptions.vsync = !scripted && !args.noVsync;
    auto window = Window::create(windowOptions);
    if (!window)
        return reportError("view", window.status());
    std::fprintf(stderr, "farfield view: %s\n", (*window)->description().c_str());
    auto hud = Hud::create();
    if (!hud)
        return reportError("view", hud.status());

    ViewerControls controls;
    controls.epsilonPixels = args.epsilon;
    controls.method = *method;
    controls.gpuBudgetBytes = *gpuBudget;
    controls.hudVisible = !args.noHud;
    // --cache-mb streams pages through the page cache; without it every page is mapped.
    controls.cacheBudgetBytes = args.cacheMb << 20;
    runtime::SessionOptions sessionOptions;
    sessionOptions.cacheBytes = args.cacheMb << 20;
    sessionOptions.renderer.gpuBudgetBytes = controls.gpuBudgetBytes;
    sessionOptions.renderer.backgroundLinear = *background;
    auto session = runtime::StreamingSession::open(args.scene, sessionOptions);
    if (!session)
        return reportError("view", session.status().withContext(args.scene));
    runtime::StreamingSession& streaming = **session;

    CameraController navigation(*initialCamera, initialPivot(*initialCamera, bounds, origin, args), bounds);

    // ---- Frame loop ------------------------------------------------------------------------
    using Clock = std::chrono::steady_clock;
    const auto start = Clock::now();
    auto last = start;
    double smoothedMs = 0.0;
    bool failed = false;
    HudInfo hudInfo;
    glm::vec3 previousEye = initialCamera->eye;
    for (int frame = 0; !(*window)->shouldClose() && (!scripted || frame < frames); ++frame) {
        const glm::ivec2 windowSize = (*window)->framebufferSize();
        const InputState& input =
                windowSize.x > 0 && windowSize.y > 0 ? (*window)->poll() : (*window)->wait();
        const auto now = Clock::now();
        const double seconds = std::chrono::duration<double>(now - last).count();
        last = now;
        smoothedMs = frame == 0 ? 1000.0 * seconds : 0.9 * smoothedMs + 100.0 * seconds;

        // Keys.
        const bool screenshot = input.pressed(Key::P) > 0 || input.pressed(Key::F12) > 0;
        if (input.pressed(Key::Escape))
            (*window)->requestClose();
        if (input.pressed(Key::Tab) % 2)
            navigation.toggleMode();
        if (input.pressed(Key::R))
            navigation.reset();
        for (int i = 0; i < input.pressed(Key::LeftBracket); ++i)
            controls.halveEpsilon();
        for (int i = 0; i < input.pressed(Key::RightBracket); ++i)
            controls.doubleEpsilon();
        if (input.pressed(Key::M) % 2)
            controls.toggleMethod();
        if (input.pressed(Key::H) % 2)
            controls.hudVisible = !controls.hudVisible;
        const std::uint64_t budgetBefore = controls.gpuBudgetBytes;
        const std::uint64_t cacheBudgetBefore = controls.cacheBudgetBytes;
        for (int i = 0; i < input.pressed(Key::Minus); ++i)
            controls.halveBudget();
        for (int i = 0; i < input.pressed(Key::Equal); ++i)
            controls.doubleBudget();
        if (controls.cacheBudgetBytes != cacheBudgetBefore)
            streaming.setCacheBudget(controls.cacheBudgetBytes);
        if (controls.gpuBudgetBytes != budgetBefore) {
            if (const Status changed = streaming.setGpuBudget(controls.gpuBudgetBytes); !changed)
                return reportError("view", changed.withContext(args.scene));
        }

        // Camera.
        if (scripted) {
            if (frame > 0) {
                navigation.orbit(script->orbitDegrees, script->elevateDegrees);
                navigation.zoom(script->zoomFactor);
            }
        } else {
            navigation.update(input, seconds, windowSize.y);
        }
        if (windowSize.x <= 0 || windowSize.y <= 0)
            continue; // minimized

        // Draw.
        runtime::FrameContext frameContext;
        frameContext.camera = navigation.camera();
        frameContext.width = windowSize.x;
        frameContext.height = windowSize.y;
        frameContext.timeSeconds = std::chrono::duration<double>(now - start).count();
        frameContext.selection.method = controls.method;
        frameContext.selection.epsilonPixels = controls.epsilonPixels;
        frameContext.selection.representation = args.representation;
        frameContext.selection.splats = args.splats;
        frameContext.occlusion = args.occlusion;
        frameContext.budgets.pageInstallsPerFrame = args.uploadsPerFrame;
        frameContext.budgets.gpuUploadsPerFrame = args.gpuUploadsPerFrame;
        const runtime::Camera& camera = frameContext.camera;
        if (streaming.streams()) {
            // Prefetch along the motion: where the camera will be in four frames at this speed.
            runtime::Camera ahead = camera;
            ahead.eye += 4.0f * (camera.eye - previousEye);
            ahead.fitClipPlanes(bounds);
            streaming.setPrefetchCamera(ahead);
        }
        previousEye = camera.eye;
        auto stats = streaming.present(frameContext);
        if (!stats)
            return reportError("view", stats.status().withContext(args.scene));
        for (const Status& failure : streaming.newFailures()) {
            reportError("view", failure.withContext(args.scene));
            failed = true;
        }
        if (scripted) {
            nlohmann::json line = nlohmann::json::parse(stats->toJson());
            line["frame"] = frame;
            std::printf("%s\n", line.dump().c_str());
        }

        // Screenshots show the scene without the HUD.
        const bool lastScriptedFrame = scripted && frame + 1 == frames;
        const bool scriptedShot = lastScriptedFrame && scriptedScreenshot->has_value();
        if (screenshot || scriptedShot) {
            Result<PendingOutput> output =
                    scriptedShot ? Result<PendingOutput>(std::move(**scriptedScreenshot))
                                 : PendingOutput::reserve(nextScreenshotPath(args.screenshotDir), OutputKind::Image);
            const Status written = output ? output->commitImage((*window)->readBackBuffer()) : output.status();
            if (written)
                std::fprintf(stderr, "farfield view: wrote %s\n", output->path().string().c_str());
            else if (scriptedShot)
                return reportError("view", written);
            else
                reportError("view", written); // a failed key-press screenshot does not end the session
        }

        if (controls.hudVisible) {
            hudInfo.navigation = navigation.mode() == NavigationMode::Orbit ? "orbit" : "fly";
            hudInfo.frameMs = smoothedMs;
            hudInfo.selectMs = stats->selectMs;
            hudInfo.drawMs = stats->drawMs;
            hudInfo.epsilonPixels = controls.epsilonPixels;
            hudInfo.method = controls.method;
            hudInfo.trianglesDrawn = stats->trianglesDrawn;
            hudInfo.cubesDrawn = stats->cubesDrawn;
            hudInfo.debt = stats->nodesDeferred;
            hudInfo.occlusion = args.occlusion.enabled;
            hudInfo.occlusionMs = stats->occlusionMs;
            hudInfo.occlusionQueries = stats->occlusionQueries;
            hudInfo.queriesWaited = stats->queriesWaited;
            hudInfo.occlusionSkipped = stats->occlusionSkipped != 0;
            hudInfo.nodesOccluded = stats->nodesOccluded;
            hudInfo.trianglesOccluded = stats->trianglesOccluded;
            hudInfo.renderRatePercent = streaming.lastFrame().renderRatePercent;
            const runtime::FrameTelemetry& telemetry = streaming.lastFrame();
            hudInfo.residentBytes = streaming.streams() ? telemetry.residentBytes : telemetry.gpuResidentBytes;
            hudInfo.budgetBytes = controls.adjustableBudget();
            hudInfo.budgetName = controls.cacheBudgetBytes ? "cache" : "gpu";
            hudInfo.requestsInFlight = telemetry.inFlight;
            hudInfo.width = windowSize.x;
            hudInfo.height = windowSize.y;
            (*hud)->draw(formatHud(hudInfo), windowSize);
        }
        (*window)->swapBuffers();
    }
    return failed ? 1 : 0;
}

} // namespace

CommandRunner addViewCommand(CLI::App& app) {
    auto args = std::make_shared<ViewArgs>();
    CLI::App* cmd =
            app.add_subcommand("view", "Explore a scene file in a window (GLFW, OpenGL 4.5 core)");
    cmd->footer("Keys: left drag orbit, middle drag pan, scroll zoom (orbit mode); W/A/S/D/Q/E "
                "move, right drag look,\n"
                "scroll speed, Shift faster (fly mode); Tab orbit/fly; R reset view; [ ] "
                "halve/double epsilon;\n"
                "M hierarchical/full; - = halve/double the budget; P or F12 screenshot; H HUD; Esc "
                "quit.\n"
                "Scripted (no human): --frames N [--script orbit:DEG] --screenshot OUT.png renders "
                "N frames, writes the\n"
                "last one (without the HUD) and exits 0; no display or no OpenGL 4.5: a message "
                "and exit 1.");
    cmd->add_option("scene", args->scene, "Scene file (.ffs)")->required();
    cmd->add_option("--size", args->size, "Window size WIDTHxHEIGHT")->capture_default_str();
    addEpsilonOption(*cmd, args->epsilon);
    addRepresentationOption(*cmd, args->representation);
    addSplatOptions(*cmd, args->splats);
    addMethodOption(*cmd, args->method);
    cmd->add_option("--cache-mb", args->cacheMb, "Stream pages through a page cache of this many MiB (0: map everything)")
            ->capture_default_str();
    cmd->add_option("--uploads-per-frame", args->uploadsPerFrame, "Finished page reads installed per frame at most")
            ->capture_default_str();
    addGpuUploadsOption(*cmd, args->gpuUploadsPerFrame);
    addOcclusionOptions(*cmd, args->occlusion);
    addGpuBudgetOption(*cmd, args->gpuBudget);
    addBackgroundOption(*cmd, args->background);
    cmd->add_option(
               "--frames",
               args->frames,
               "Render this many frames, then exit (0: until the window closes)")
            ->capture_default_str();
    cmd->add_option(
            "--screenshot",
            args->screenshot,
            "Write the last frame here (.png, ...) and exit; implies --frames 1 if unset");
    args->screenshotDirOption =
            cmd->add_option("--screenshot-dir", args->screenshotDir, "Where P/F12 write screenshot-NNNN.png")
                    ->capture_default_str();
    cmd->add_option(
            "--script",
            args->script,
            "Camera motion per frame after the first, e.g. orbit:5,elevate:1,zoom:0.98 (with "
            "--frames)");
    cmd->add_flag("--no-hud", args->noHud, "Start with the HUD hidden (H toggles it)");
    cmd->add_flag(
            "--no-vsync", args->noVsync, "Do not wait for the display's refresh between frames");
    addCameraOptions(*cmd, args->camera);
    return [args]() { return runView(*args); };
}

} // namespace ff::viewer
