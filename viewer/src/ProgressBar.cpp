#include "ProgressBar.h"

#include <cstdio>
#include <unistd.h>

namespace ff::viewer {

ProgressBar::ProgressBar() : mEnabled(::isatty(STDERR_FILENO) == 1) {}

ProgressBar::~ProgressBar() { finish(); }

void ProgressBar::update(const std::string& phase, std::uint64_t done, std::uint64_t total) {
    if (!mEnabled)
        return;
    const auto now = std::chrono::steady_clock::now();
    if (mDrawn && done != total && now - mLast < std::chrono::milliseconds(100))
        return;
    mLast = now;
    mDrawn = true;
    constexpr int kWidth = 30;
    if (total == 0) {
        std::fprintf(stderr, "\r%-10s %llu\033[K", phase.c_str(), static_cast<unsigned long long>(done));
    } else {
        const double fraction = static_cast<double>(done) / static_cast<double>(total);
        const int filled = static_cast<int>(fraction * kWidth);
        std::string bar(static_cast<std::size_t>(filled), '#');
        bar.resize(kWidth, '.');
        std::fprintf(stderr, "\r%-10s [%s] %5.1f%%\033[K", phase.c_str(), bar.c_str(), 100.0 * fraction);
    }
    std::fflush(stderr);
}

void ProgressBar::finish() {
    if (mEnabled && mDrawn) {
        std::fprintf(stderr, "\r\033[K");
        std::fflush(stderr);
    }
    mDrawn = false;
}

} // namespace ff::viewer
