#include <ff/storage/ProcessMemory.h>

#include <cstdio>
#include <cstring>

namespace ff::storage {

ProcessMemory readProcessMemory() noexcept {
    ProcessMemory memory;
    std::FILE* status = std::fopen("/proc/self/status", "re");
    if (status == nullptr)
        return memory;
    char line[256];
    while (std::fgets(line, sizeof(line), status) != nullptr) {
        // "VmHWM:     12345 kB": the number after the colon, in kB.
        unsigned long long kilobytes = 0;
        if (std::sscanf(line, "VmHWM: %llu", &kilobytes) == 1)
            memory.peakRssBytes = kilobytes * 1024;
        else if (std::sscanf(line, "RssAnon: %llu", &kilobytes) == 1)
            memory.anonBytes = kilobytes * 1024;
        else if (std::sscanf(line, "RssFile: %llu", &kilobytes) == 1)
            memory.fileBytes = kilobytes * 1024;
    }
    std::fclose(status);
    return memory;
}

} // namespace ff::storage
