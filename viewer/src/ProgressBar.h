#pragma once

#include <chrono>
#include <cstdint>
#include <string>

namespace ff::viewer {

/**
 * A one-line progress bar on stderr, drawn only when stderr is a terminal (batch jobs and CI
 * logs stay clean). Redraws at most ten times a second.
 */
class ProgressBar {
public:
    ProgressBar();
    ~ProgressBar();
    ProgressBar(const ProgressBar&) = delete;
    ProgressBar& operator=(const ProgressBar&) = delete;

    /** total 0 = unknown (shows a count). */
    void update(const std::string& phase, std::uint64_t done, std::uint64_t total);
    void finish();

private:
    bool mEnabled;
    bool mDrawn = false;
    std::chrono::steady_clock::time_point mLast;
};

} // namespace ff::viewer
