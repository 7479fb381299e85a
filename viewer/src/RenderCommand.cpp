#include "CameraFlags.h"
#include "Commands.h"
#include "FrameFlags.h"
#include "OutputFile.h"

#include <ff/runtime/OffscreenContext.h>
#include <ff/runtime/StreamingSession.h>
#include <ff/runtime/Units.h>

#include <nlohmann/json.hpp>

#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace ff::viewer {

namespace {

struct RenderArgs {
    std::string scene;
    std::string output;
    std::string size = "640x480";
    float epsilon = 1.0f;
    runtime::Representation representation = runtime::Representation::Auto;
    runtime::SplatStyle splats;
    std::string method = "hierarchical";
    std::string cubeDraw = "auto";
    float cubeAnisotropy = 1.0f;
    int supersample = 1;
    int frames = 1;
    std::string stats;
    std::string background = "0.70,0.75,0.83";
    std::string gpuBudget = "512MiB";
    bool coverage = false;
    runtime::OcclusionOptions occlusion;
    bool oracle = false;
    runtime::CameraOptions camera;
};

int runRender(const RenderArgs& args) {
    auto size = runtime::parseImageSize(args.size);
    if (!size)
        return reportError("render", size.status().withContext("--size"));
    const std::optional<runtime::Method> method = runtime::parseMethod(args.method);
    if (!method)
        return reportError("render", Status(ErrorCode::InvalidArgument, "--method must be hierarchical or full"));
    if (!(args.epsilon >= 0.0f))
        return reportError("render", Status(ErrorCode::InvalidArgument, "--epsilon must be >= 0"));
    if (args.supersample < 1 || args.supersample > 16 || args.frames < 1)
        return reportError("render", Status(ErrorCode::InvalidArgument, "--supersample must be 1..16 and --frames >= 1"));
    auto background = runtime::parseVec3(args.background);
    if (!background)
        return reportError("render", background.status().withContext("--background"));
    auto gpuBudget = runtime::parseByteSize(args.gpuBudget);
    if (!gpuBudget)
        return reportError("render", gpuBudget.status().withContext("--gpu-budget"));

    // Outputs first: an unwritable path fails before the work, not after it.
    auto image = reserveIfNamed(args.output, OutputKind::Image);
    if (!image)
        return reportError("render", image.status());
    auto statsFile = reserveIfNamed(args.stats, OutputKind::Text);
    if (!statsFile)
        return reportError("render", statsFile.status().withContext("--stats"));

    auto context = runtime::OffscreenContext::create();
    if (!context)
        return reportError("render", context.status());
    runtime::SessionOptions sessionOptions;
    sessionOptions.renderer.gpuBudgetBytes = *gpuBudget;
    sessionOptions.renderer.backgroundLinear = *background;
    auto session = runtime::StreamingSession::open(args.scene, sessionOptions);
    if (!session)
        return reportError("render", session.status().withContext(args.scene));
    auto camera = args.camera.resolve((*session)->scene());
    if (!camera)
        return reportError("render", camera.status());

    runtime::FrameContext frameContext;
    frameContext.camera = *camera;
    frameContext.width = size->x;
    frameContext.height = size->y;
    frameContext.supersample = args.supersample;
    frameContext.selection.method = *method;
    frameContext.selection.epsilonPixels = args.epsilon;
    frameContext.selection.representation = args.representation;
    frameContext.selection.splats = args.splats;
    frameContext.selection.cubeStyle =
            runtime::parseCubeStyle(args.cubeDraw).value_or(runtime::CubeStyle::Auto); // checked by CLI11
    frameContext.selection.maxCubeAnisotropy = args.cubeAnisotropy;
    frameContext.occlusion = args.occlusion;
    nlohmann::json frames = nlohmann::json::array();
    Result<runtime::Frame> frame = Status(ErrorCode::Internal, "no frame rendered");
    std::vector<Status> failures;
    for (int f = 0; f < args.frames; ++f) {
        frame = args.oracle ? (*session)->renderOracle(frameContext) : (*session)->render(frameContext);
        if (!frame)
            return reportError("render", frame.status().withContext(args.scene));
        const auto& fresh = (*session)->newFailures();
        failures.insert(failures.end(), fresh.begin(), fresh.end());
        nlohmann::json stats = nlohmann::json::parse(frame->stats.toJson());
        stats["frame"] = f;
        std::printf("%s\n", stats.dump().c_str());
        frames.push_back(stats);
    }
    if (*image) {
        if (const Status written = (*image)->commitImage(frame->image, args.coverage); !written)
            return reportError("render", written);
    }
    if (*statsFile) {
        const nlohmann::json out = {{"scene", args.scene},
                                    {"method", args.method},
                                    {"epsilon", args.epsilon},
                                    {"occlusion", args.oracle ? "oracle" : args.occlusion.enabled ? "on" : "off"},
                                    {"width", size->x},
                                    {"height", size->y},
                                    {"supersample", args.supersample},
                                    {"frames", frames}};
        if (const Status written = (*statsFile)->commitText(out.dump(2) + "\n"); !written)
            return reportError("render", written);
    }
    // Unreadable pages were drawn with their ancestors' cubes; the image exists, but the file
    // is damaged and the exit status says so.
    for (const Status& failure : failures)
        reportError("render", failure.withContext(args.scene));
    return failures.empty() ? 0 : 1;
}

} // namespace

CommandRunner addRenderCommand(CLI::App& app) {
    auto args = std::make_shared<RenderArgs>();
    CLI::App* cmd = app.add_subcommand("render", "Render a scene file headless (OSMesa) to an image");
    cmd->add_option("scene", args->scene, "Scene file (.ffs)")->required();
    cmd->add_option("-o,--output", args->output, "Image to write (.png, .exr, .tif, ...)");
    cmd->add_option("--size", args->size, "Image size WIDTHxHEIGHT")->capture_default_str();
    addEpsilonOption(*cmd, args->epsilon);
    addRepresentationOption(*cmd, args->representation);
    addSplatOptions(*cmd, args->splats);
    addMethodOption(*cmd, args->method);
    addCubeDrawOption(*cmd, args->cubeDraw);
    addCubeAnisotropyOption(*cmd, args->cubeAnisotropy);
    addOcclusionOptions(*cmd, args->occlusion, &args->oracle);
    cmd->add_option("--supersample", args->supersample, "Render NxN samples per pixel (a reference)")->capture_default_str();
    cmd->add_option("--frames", args->frames, "Render the view this many times (timing; first frame uploads)")->capture_default_str();
    cmd->add_option("--stats", args->stats, "Write the per-frame statistics as JSON here (also printed on stdout)");
    addBackgroundOption(*cmd, args->background);
    addGpuBudgetOption(*cmd, args->gpuBudget);
    cmd->add_flag("--coverage-alpha", args->coverage, "Keep coverage as the image's alpha channel");
    addCameraOptions(*cmd, args->camera);
    return [args]() { return runRender(*args); };
}

} // namespace ff::viewer
