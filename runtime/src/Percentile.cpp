#include <ff/runtime/Percentile.h>

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace ff::runtime {

double percentile(std::vector<double> values, double p) {
    if (values.empty())
        return 0.0;
    std::sort(values.begin(), values.end());
    // Rank ceil(p n), from 1; p = 0 asks for rank 0, which is the first value too.
    const auto rank = static_cast<std::size_t>(
            std::ceil(std::clamp(p, 0.0, 1.0) * static_cast<double>(values.size())));
    return values[std::min(rank == 0 ? 0 : rank - 1, values.size() - 1)];
}

} // namespace ff::runtime
