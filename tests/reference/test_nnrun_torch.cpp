// nnrun --model stixelnext against the PyTorch model of stixel_head_ref.py (the
// authors' StixelNExT++: ConvNeXt-Tiny features, row pooling, head): the prediction
// [1, A, 64, U] after the sigmoid within 1e-5, and its --dump ending in that same
// prediction under the head's module name `classifier`.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include "tests/reference/torch_ref.h"

namespace {

constexpr double kTol = 1e-5;

std::string temp(const std::string& name) {
  return testing::TempDir() + "nnrun_torch_" + std::to_string(static_cast<long>(::getpid())) + "_" + name;
}

void check(const std::string& variant, int attributes) {
  const std::string weights = reftest::ref_path("stixel_" + variant + "_weights.safetensors");
  const std::string input = reftest::ref_path("stixel_case_" + variant + "_small.safetensors");
  weights::SafeTensors c = reftest::load_ref("stixel_case_" + variant + "_small.safetensors");
  const std::string y = temp(variant + "_y.safetensors"), d = temp(variant + "_d.safetensors"), err = temp("err");
  const std::string cmd = std::string(NNRUN_PATH) + " --model stixelnext --weights " + weights + " --input " + input +
                          " --output " + y + " --dump " + d + " --threads 2 --quiet 2>" + err;
  const int status = std::system(cmd.c_str());
  std::stringstream e;
  e << std::ifstream(err).rdbuf();
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << e.str();
  weights::SafeTensors out = weights::SafeTensors::load(y);
  // small: 256 x 640 input, U = 640 / 8 = 80 columns (no stixelnext.* metadata).
  ASSERT_EQ(out.info("prediction").shape, (std::vector<std::int64_t>{1, attributes, 64, 80}));
  ASSERT_EQ(out.info("prediction").shape, c.info("expected").shape);
  const auto p = out.f32("prediction");
  reftest::expect_close_abs(p.data(), c.f32("expected"), kTol, "nnrun stixelnext " + variant);
  weights::SafeTensors dump = weights::SafeTensors::load(d);
  EXPECT_TRUE(dump.f32("classifier") == p);
  EXPECT_EQ(dump.info("features").shape, (std::vector<std::int64_t>{1, 768, 8, 20}));
  for (const auto& f : {y, d, err}) std::remove(f.c_str());
}

TEST(NnrunTorch, StixelNExTV4) { check("v4", 4); }
TEST(NnrunTorch, StixelNExTV1) { check("v1", 3); }

}  // namespace
