// nnrun --dump on the detectors against torchvision's own outputs of detector_ref.py:
// the dump's transform[0] (GeneralizedRCNNTransform's batched image, NCHW) is the
// reference's transformed image and its rpn[0][0] the RPN proposals (matched as the
// detector tests match them: torchvision breaks score ties its own way), bitwise equal
// to the --dump-proposals output of the same run; the pyramid and head names are there.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include "tests/detection/match.h"
#include "tests/reference/torch_ref.h"

namespace {

std::string temp(const std::string& name) {
  return testing::TempDir() + "nnrun_det_dump_" + std::to_string(static_cast<long>(::getpid())) + "_" + name;
}

void check(const std::string& key, const std::string& model, const std::string& filter,
           const std::vector<std::string>& names) {
  const std::string weights = reftest::ref_path("det_" + key + "_weights.safetensors");
  const std::string input = reftest::ref_path("det_" + key + "_odd.safetensors");
  weights::SafeTensors c = reftest::load_ref("det_" + key + "_odd.safetensors");
  const std::string y = temp(key + "_y.safetensors"), d = temp(key + "_d.safetensors"), err = temp(key + "_err");
  std::string cmd = std::string(NNRUN_PATH) + " --model " + model + " --weights " + weights + " --input " + input +
                    " --output " + y + " --dump " + d + " --dump-proposals --threads 2 --quiet";
  if (!filter.empty()) cmd += " --dump-filter '" + filter + "'";
  const int status = std::system((cmd + " 2>" + err).c_str());
  std::stringstream e;
  e << std::ifstream(err).rdbuf();
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << e.str();
  weights::SafeTensors dump = weights::SafeTensors::load(d), out = weights::SafeTensors::load(y);
  EXPECT_EQ(dump.metadata().at("dump.model"), model);
  ASSERT_EQ(dump.info("transform[0]").shape, c.info("transformed").shape);
  const auto t = dump.f32("transform[0]");
  reftest::expect_close_abs(t.data(), c.f32("transformed"), 1e-5, key + " transform[0]");
  EXPECT_TRUE(dump.f32("rpn[0][0]") == out.f32("proposals"));
  const auto ours = dettest::to_boxes(dump.f32("rpn[0][0]")), ref = dettest::to_boxes(c.f32("proposals"));
  const auto a = dettest::match(ref, {}, {}, ours, {}, {}, 0.99, 0);
  EXPECT_GE(a.fraction(), 0.99) << key << " torchvision proposals unmatched:" << a.unmatched;
  for (const auto& n : names) EXPECT_TRUE(dump.has(n)) << n;
  for (const auto& f : {y, d, err}) std::remove(f.c_str());
}

TEST(NnrunDumpTorch, MobileNetV3Large320) {
  check("mnv3_320", "fasterrcnn_mobilenet_v3_large_320_fpn", "",
        {"backbone.body.0", "backbone.body.13", "backbone.body.16", "backbone.body[0]", "backbone.body[1]",
         "backbone.fpn[0]", "backbone.fpn[1]", "backbone.fpn[pool]", "rpn.head.conv#2", "rpn.head[0][2]",
         "roi_heads.box_roi_pool", "roi_heads.box_head", "roi_heads.box_predictor.cls_score",
         "roi_heads.box_predictor.bbox_pred"});
}

// ResNet-50's full dump is gigabytes at 800 px: the filter keeps the boundaries.
TEST(NnrunDumpTorch, ResNet50Filtered) {
  check("r50", "fasterrcnn_resnet50_fpn", "^(transform|rpn\\[0\\]|backbone\\.fpn\\[|backbone\\.body\\.layer[1-4]$)",
        {"backbone.body.layer1", "backbone.body.layer4", "backbone.fpn[3]", "backbone.fpn[pool]"});
}

}  // namespace
