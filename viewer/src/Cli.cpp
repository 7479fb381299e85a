#include <ff/viewer/Cli.h>

#include "Commands.h"

#include <cstdio>
#include <map>

namespace ff::viewer {

int reportError(const char* verb, const Status& status) {
    std::fprintf(stderr, "farfield %s: %s\n", verb, status.toString().c_str());
    return status.code() == ErrorCode::InvalidArgument ? 2 : 1;
}

int runCli(int argc, char** argv) {
    CLI::App app("farfield: out-of-core rendering of scenes larger than memory", "farfield");
    app.require_subcommand(1);
    std::map<std::string, CommandRunner> runners = {
            {"build", addBuildCommand(app)},
            {"render", addRenderCommand(app)},
            {"check", addCheckCommand(app)},
            {"bench", addBenchCommand(app)},
            {"replay", addReplayCommand(app)},
            {"path", addPathCommand(app)},
            {"view", addViewCommand(app)},
            {"stats", addStatsCommand(app)},
    };
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return app.exit(e);
    }
    for (CLI::App* sub : app.get_subcommands())
        return runners.at(sub->get_name())();
    return 2;
}

} // namespace ff::viewer
