#include "Commands.h"

namespace ff::viewer {

CommandRunner addBenchCommand(CLI::App& app) {
    CLI::App* cmd = app.add_subcommand("bench", "Benchmarks: table2, forest, build (CSV + PNG charts)");
    (void)cmd;
    return []() { return reportError("bench", Status(ErrorCode::Unsupported, "not built yet")); };
}

} // namespace ff::viewer
