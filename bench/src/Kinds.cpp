// The one table of benchmark kinds: a scenario's "kind" names one row, which prepares it.

#include <ff/bench/Benchmarks.h>

#include <array>
#include <utility>

namespace ff::bench {

namespace {

using Prepare = Result<BenchRun> (*)(const Scenario&);

constexpr std::array<std::pair<const char*, Prepare>, 10> kKinds = {{
        {"table2", prepareTable2},
        {"forest", prepareForest},
        {"build", prepareBuild},
        {"paging", preparePaging},
        {"views", prepareViews},
        {"path", preparePath},
        {"replay", prepareReplay},
        {"render", prepareRender},
        {"codec", prepareCodec},
        {"format", prepareFormat},
}};

} // namespace

std::vector<std::string> scenarioKinds() {
    std::vector<std::string> names;
    for (const auto& [name, prepare] : kKinds)
        names.emplace_back(name);
    return names;
}

Result<BenchRun> prepareScenario(const Scenario& scenario) {
    for (const auto& [name, prepare] : kKinds) {
        if (scenario.kind == name)
            return prepare(scenario);
    }
    return Status(
            ErrorCode::InvalidArgument,
            scenario.where() + ": unknown kind \"" + scenario.kind + "\"");
}

} // namespace ff::bench
