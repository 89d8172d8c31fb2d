// A fresh folder per test case under the build tree, so ctest may run the cases
// of one binary in parallel without sharing files.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

namespace appstest {

inline std::string test_dir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::filesystem::path dir = std::filesystem::path(ROADNN_BINARY_DIR) / "test_tmp" / "apps" /
                              (std::string(info->test_suite_name()) + "." + info->name());
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir.string();
}

}  // namespace appstest
