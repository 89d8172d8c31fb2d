// Access to the reference files the tests/reference/*.py scripts write at test time.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include "weights/safetensors.h"

// In a test of a large input: skip, saying why, in the small-size run.
#define ROADNN_SKIP_LARGE_INPUT()                                                               \
  if (reftest::small_sizes_only())                                                             \
  GTEST_SKIP() << "large input: not part of the small-size run (ROADNN_TEST_SIZES=small, "    \
                  "the cross build's emulated tests)"

// In a test the small-size run leaves to the host suites because of its cost under
// emulation, not its input size: skip, saying why and what covers its kernels there.
#define ROADNN_SKIP_IN_SMALL_RUN(why)                                                          \
  if (reftest::small_sizes_only())                                                             \
  GTEST_SKIP() << "left to the host suites in the small-size run (ROADNN_TEST_SIZES=small): " \
               << why

namespace reftest {

// ROADNN_TEST_SIZES=small, which CMake sets on every test of a cross build (its tests run
// under emulation: scripts/test_arm64; docs/ENGINEERING.md): the model tests run their
// small cases only; the reference scripts write only those (refcommon.small_sizes()).
inline bool small_sizes_only() {
  const char* v = std::getenv("ROADNN_TEST_SIZES");
  return v && std::string(v) == "small";
}

inline std::string ref_path(const std::string& file) { return std::string(ROADNN_REF_DIR) + "/" + file; }

// Loads a reference file, failing the test with a hint when the generator did not run.
inline weights::SafeTensors load_ref(const std::string& file) {
  const std::string path = ref_path(file);
  std::ifstream probe(path);
  if (!probe)
    throw std::runtime_error(path + " is missing: its PyTorch generator (ctest fixture ref_*) failed or did not run; "
                             "it needs python3-torch and python3-torchvision for /usr/bin/python3 "
                             "(apt-get install -y python3-torch python3-torchvision python3-numpy)");
  return weights::SafeTensors::load(path);
}

struct Diff {
  double max_abs = 0, max_ref = 0;
  std::size_t worst = 0;
};

inline Diff diff(const float* ours, const std::vector<float>& ref) {
  Diff d;
  for (std::size_t i = 0; i < ref.size(); ++i) {
    const double e = std::fabs(static_cast<double>(ours[i]) - ref[i]);
    if (!(e <= d.max_abs)) {  // also catches NaN
      d.max_abs = std::isnan(e) ? INFINITY : e;
      d.worst = i;
    }
    d.max_ref = std::max(d.max_ref, std::fabs(static_cast<double>(ref[i])));
  }
  return d;
}

// max |ours - torch| <= rel * max |torch|
inline void expect_close_rel_max(const float* ours, const std::vector<float>& ref, double rel,
                                 const std::string& what) {
  Diff d = diff(ours, ref);
  EXPECT_LE(d.max_abs, rel * d.max_ref)
      << what << ": max |ours - torch| = " << d.max_abs << " at element " << d.worst << " (ours "
      << ours[d.worst] << ", torch " << ref[d.worst] << "), max |torch| = " << d.max_ref
      << ", allowed " << rel * d.max_ref;
}

// max |ours - torch| <= tol
inline void expect_close_abs(const float* ours, const std::vector<float>& ref, double tol,
                             const std::string& what) {
  Diff d = diff(ours, ref);
  EXPECT_LE(d.max_abs, tol) << what << ": max |ours - torch| = " << d.max_abs << " at element "
                            << d.worst << " (ours " << ours[d.worst] << ", torch " << ref[d.worst] << ")";
}

}  // namespace reftest
