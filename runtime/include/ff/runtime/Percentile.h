#pragma once

#include <vector>

namespace ff::runtime {

/**
 * The nearest-rank percentile of `values` (p in [0, 1]): the smallest value with at least p of
 * the values at or below it; p = 0 gives the minimum, p = 1 the maximum, 0 for no values.
 * The one definition behind every p50/p95/p99 that replay and the benchmarks report.
 */
double percentile(std::vector<double> values, double p);

} // namespace ff::runtime
