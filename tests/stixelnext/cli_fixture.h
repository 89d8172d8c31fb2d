// The stixelnext test fixture: a temporary folder with a small ConvNeXt + stixel
// head (64x96 input), a 96x64 PNG and a calibration; run() drives the program.
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "apps/common/image_io.h"
#include "nn/models/convnext.h"
#include "nn/models/stixel_head.h"
#include "nn/models/synthetic_weights.h"

namespace stixelnext_test {

inline std::string slurp(const std::string& path) {
  std::stringstream s;
  s << std::ifstream(path).rdbuf();
  return s.str();
}

class StixelnextCli : public testing::Test {
 protected:
  void SetUp() override {
    char tmpl[] = "/tmp/stixelnext_test_XXXXXX";
    ASSERT_NE(mkdtemp(tmpl), nullptr);
    dir_ = tmpl;
    write_weights("w.safetensors", nn::StixelHeadVariant::V4);
    std::vector<std::uint8_t> px(64 * 96 * 3);
    for (std::size_t i = 0; i < px.size(); ++i) px[i] = static_cast<std::uint8_t>((i * 37) % 251);
    imageio::save_png(path("img.png"), px.data(), 96, 64, 3);
    write_text("cam.json", R"({"K": [80, 0, 47.5, 0, 80, 31.5, 0, 0, 1], "width": 96, "height": 64})");
  }
  void TearDown() override { std::system(("rm -rf " + dir_).c_str()); }

  std::string path(const std::string& f) const { return dir_ + "/" + f; }
  void write_text(const std::string& f, const std::string& text) { std::ofstream(path(f)) << text; }
  // `metadata` replaces the default 64 x 96 input size keys (pass {} for none).
  void write_weights(const std::string& f, nn::StixelHeadVariant v,
                     const std::vector<std::pair<std::string, std::string>>& metadata =
                         {{"stixelnext.input_height", "64"}, {"stixelnext.input_width", "96"}}) {
    nn::ConvNeXtConfig cfg{{8, 12, 20, 28}, {1, 1, 1, 1}};
    auto specs = nn::convnext_tensor_specs(cfg, "features.");
    for (auto& s : nn::stixel_head_tensor_specs(v, 28, "classifier.")) specs.push_back(s);
    auto w = nn::synthetic_weights(specs, 5);
    for (const auto& [k, val] : metadata) w.set_metadata(k, val);
    w.write(path(f));
  }
  int run(const std::string& args) {
    const std::string cmd = std::string(STIXELNEXT_PATH) + " --quiet --threads 2 --out-dir " + path("out") + " " + args +
                            " >" + path("stdout") + " 2>" + path("stderr");
    int status = std::system(cmd.c_str());
    err_ = slurp(path("stderr"));
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }
  bool exists(const std::string& f) const { return std::ifstream(path(f)).good(); }
  void expect_error_line(const std::string& must_contain) {
    EXPECT_NE(err_.find(must_contain), std::string::npos) << "expected '" << must_contain << "' in: " << err_;
    EXPECT_EQ(std::count(err_.begin(), err_.end(), '\n'), 1) << err_;
  }

  std::string dir_, err_;
};

}  // namespace stixelnext_test
