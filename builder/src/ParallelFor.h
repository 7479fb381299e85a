#pragma once

#include <ff/storage/Status.h>

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <future>
#include <vector>

namespace ff::builder {

/**
 * Runs work(k) for every k in [0, count) on up to `threads` threads, this one among them, each
 * taking the next k as it finishes one. makeWork() gives each thread its own callable (and so
 * its own scratch: an encoder, a baker). The first error is returned; the others still finish
 * what they took. The results must not depend on which thread ran what.
 */
template <class MakeWork>
[[nodiscard]] Status parallelFor(std::size_t count, unsigned threads, const MakeWork& makeWork) {
    std::atomic<std::size_t> next{0};
    const auto worker = [&]() -> Status {
        auto work = makeWork();
        Status status = Status::ok();
        for (std::size_t k = next++; k < count; k = next++) {
            Status s = work(k);
            if (status.isOk() && !s.isOk())
                status = std::move(s);
        }
        return status;
    };
    const std::size_t helpers =
            std::min<std::size_t>(std::max(threads, 1u), std::max<std::size_t>(count, 1)) - 1;
    std::vector<std::future<Status>> running;
    for (std::size_t t = 0; t < helpers; ++t)
        running.push_back(std::async(std::launch::async, worker));
    Status status = worker();
    for (auto& r : running) {
        Status s = r.get();
        if (status.isOk())
            status = std::move(s);
    }
    return status;
}

} // namespace ff::builder
