#include "Commands.h"
#include "ProgressBar.h"

#include <ff/storage/HierarchyCheck.h>
#include <ff/storage/SceneFile.h>

#include <nlohmann/json.hpp>

#include <cstdio>
#include <memory>
#include <optional>
#include <string>

namespace ff::viewer {

namespace {

struct CheckArgs {
    std::string scene;
    bool json = false;
};

int runCheck(const CheckArgs& args) {
    ProgressBar progress;
    auto scene = storage::SceneFile::open(args.scene);
    Status status = scene ? Status::ok() : scene.status();
    if (scene)
        status = (*scene)->verifyAll([&progress](std::uint64_t done, std::uint64_t total) { progress.update("check", done, total); });
    // Version 2 is walked too: a checksum says a page is as written, not that its records
    // point where they should.
    std::optional<storage::HierarchySummary> hierarchy;
    if (status.isOk() && (*scene)->formatVersion() == storage::kFormatVersion2) {
        Result<storage::HierarchySummary> walked = storage::checkHierarchyV2(
                **scene, (*scene)->source(), [&progress](std::uint64_t done, std::uint64_t total) {
                    progress.update("hierarchy", done, total);
                });
        if (walked)
            hierarchy = *walked;
        else
            status = walked.status();
    }
    progress.finish();
    if (args.json) {
        nlohmann::json out = {{"scene", args.scene}, {"ok", status.isOk()}};
        if (scene) {
            out["pages"] = (*scene)->pageCount();
            out["format_version"] = (*scene)->formatVersion();
        }
        if (hierarchy)
            out["hierarchy"] = {{"nodes", hierarchy->nodes},
                                {"representations", hierarchy->representations},
                                {"clusters", hierarchy->clusters},
                                {"cluster_pages", hierarchy->clusterPages},
                                {"triangles", hierarchy->triangles},
                                {"stand_ins", hierarchy->standIns},
                                {"stand_in_triangles", hierarchy->standInTriangles},
                                {"splat_sets", hierarchy->splatSets},
                                {"splats", hierarchy->splats},
                                {"splat_triangles", hierarchy->splatTriangles}};
        if (!status.isOk()) {
            out["error"] = status.message();
            out["code"] = errorCodeName(status.code());
        }
        std::printf("%s\n", out.dump().c_str());
    }
    if (!status.isOk())
        return reportError("check", status.withContext(args.scene));
    if (!args.json) {
        std::printf("%s: ok, %llu pages of %u bytes verified\n", args.scene.c_str(),
                    static_cast<unsigned long long>((*scene)->pageCount()), (*scene)->pageSize());
        if (hierarchy)
            std::printf("format 2: %llu nodes, %llu clusters in %llu pages, %llu triangles decoded, "
                        "%llu stand-ins of %llu triangles, %llu splat sets of %llu splats and %llu triangles\n",
                        static_cast<unsigned long long>(hierarchy->nodes),
                        static_cast<unsigned long long>(hierarchy->clusters),
                        static_cast<unsigned long long>(hierarchy->clusterPages),
                        static_cast<unsigned long long>(hierarchy->triangles),
                        static_cast<unsigned long long>(hierarchy->standIns),
                        static_cast<unsigned long long>(hierarchy->standInTriangles),
                        static_cast<unsigned long long>(hierarchy->splatSets),
                        static_cast<unsigned long long>(hierarchy->splats),
                        static_cast<unsigned long long>(hierarchy->splatTriangles));
    }
    return 0;
}

} // namespace

CommandRunner addCheckCommand(CLI::App& app) {
    auto args = std::make_shared<CheckArgs>();
    CLI::App* cmd = app.add_subcommand("check", "Verify every page of a scene file (checksums, structure); names the first bad page");
    cmd->add_option("scene", args->scene, "Scene file (.ffs)")->required();
    cmd->add_flag("--json", args->json, "Print the result as JSON");
    return [args]() { return runCheck(*args); };
}

} // namespace ff::viewer
