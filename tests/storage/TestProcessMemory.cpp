// The /proc/self/status reader behind the builder's peak RSS and replay's memory split.

#include <ff/storage/ProcessMemory.h>

#include <gtest/gtest.h>

#include <cstring>
#include <memory>

namespace ff::storage {
namespace {

TEST(ProcessMemoryTest, SeesMemoryThisProcessTouches) {
    const ProcessMemory before = readProcessMemory();
    ASSERT_GT(before.anonBytes, 0u);
    ASSERT_GT(before.fileBytes, 0u); // the test executable itself
    ASSERT_GE(before.peakRssBytes, before.anonBytes);
    constexpr std::size_t kBytes = 64u << 20;
    auto block = std::make_unique<char[]>(kBytes);
    std::memset(block.get(), 1, kBytes); // resident only once written
    const ProcessMemory after = readProcessMemory();
    EXPECT_GE(after.anonBytes, before.anonBytes + kBytes / 2);
    EXPECT_GE(after.peakRssBytes, before.peakRssBytes + kBytes / 2);
    EXPECT_EQ(block[kBytes - 1], 1);
}

} // namespace
} // namespace ff::storage
