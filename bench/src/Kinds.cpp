// Which prepare function runs a scenario: the one table of benchmark kinds.

#include <ff/bench/Benchmarks.h>

namespace ff::bench {

Result<BenchRun> prepareScenario(const Scenario& scenario) {
    if (scenario.kind == "table2")
        return prepareTable2(scenario);
    if (scenario.kind == "forest")
        return prepareForest(scenario);
    if (scenario.kind == "build")
        return prepareBuild(scenario);
    if (scenario.kind == "paging")
        return preparePaging(scenario);
    if (scenario.kind == "views")
        return prepareViews(scenario);
    if (scenario.kind == "path")
        return preparePath(scenario);
    if (scenario.kind == "replay")
        return prepareReplay(scenario);
    return Status(
            ErrorCode::InvalidArgument,
            scenario.where() + ": unknown kind \"" + scenario.kind + "\"");
}

} // namespace ff::bench
