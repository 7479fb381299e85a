#pragma once

// The process's memory as the kernel counts it (/proc/self/status), for the builder's report and
// the runtime's telemetry. Here, in the root module, because both sides report it and storage is
// the one module they share.

#include <cstdint>

namespace ff::storage {

struct ProcessMemory {
    std::uint64_t peakRssBytes = 0; ///< VmHWM: the high-water mark of resident memory
    std::uint64_t anonBytes = 0;    ///< RssAnon: heap, stacks, anonymous mappings
    std::uint64_t fileBytes = 0;    ///< RssFile: mapped files (the executable, its libraries)
};

/** Reads /proc/self/status; fields it cannot read (no /proc) stay 0. */
ProcessMemory readProcessMemory() noexcept;

} // namespace ff::storage
