#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

namespace ff::runtime::test {

/** A fresh, empty directory for the running test. */
inline std::filesystem::path freshDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    const std::filesystem::path dir = std::filesystem::path(FF_TEST_TMP_DIR) /
                                      (std::string(info->test_suite_name()) + "." + info->name());
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    return dir;
}

} // namespace ff::runtime::test
