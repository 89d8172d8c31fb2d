// The detectron2 box source (`shle --boxes detector --detector-model
// detectron2_faster_rcnn_r50_fpn`): the model's own detections after the filter, with
// detectron2's 0-based labels, and its errors.
#include <gtest/gtest.h>

#include "nn/models/detection/faster_rcnn.h"
#include "nn/models/synthetic_weights.h"
#include "shle/detectron2_box_source.h"
#include "shle/error.h"
#include "tests/error_of.h"

namespace {

namespace det = nn::detection;
using testutil::error_of;

// Seeded random weights under detectron2's names, K = 2 foreground classes, made once.
const weights::SafeTensors& random_weights() {
  static const weights::SafeTensors st = weights::SafeTensors::from_bytes(
      nn::synthetic_weights(det::detectron2_faster_rcnn_tensor_specs(3), 6).bytes(), "d2.safetensors");
  return st;
}

shle::RgbImage test_image(int w, int h) {
  shle::RgbImage img;
  img.width = w, img.height = h;
  img.rgb.resize(static_cast<std::size_t>(w) * h * 3);
  for (std::size_t i = 0; i < img.rgb.size(); ++i) img.rgb[i] = static_cast<std::uint8_t>((i * 2654435761u) >> 11);
  return img;
}

TEST(Detectron2BoxSource, MatchesTheModelsDetections) {
  shle::DetectorOptions opt;
  opt.score_threshold = 0.0;
  shle::Detectron2BoxSource src(random_weights(), opt);
  EXPECT_EQ(src.name(), "detector");
  EXPECT_TRUE(src.needs_image());
  EXPECT_EQ(src.num_classes(), 2);
  EXPECT_EQ(src.labels(), (std::vector<int>{0, 1}));  // 0-based: class 0 is a device, not the background

  const shle::RgbImage img = test_image(96, 64);
  shle::FrameContext frame;
  frame.index = 0;
  frame.image = &img;
  const std::vector<shle::Candidate> got = src.candidates(frame);
  det::Detectron2FasterRcnnConfig cfg;
  cfg.roi_heads.score_thresh = 0.0f;
  det::Detectron2FasterRcnn model(random_weights(), cfg);
  model.plan(64, 96);
  const std::vector<shle::Candidate> want =
      shle::detections_to_candidates(model.forward(img.rgb.data()), {0, 1}, 0.0);
  ASSERT_EQ(got.size(), want.size());
  std::printf("%zu candidates\n", got.size());
  for (std::size_t i = 0; i < got.size(); ++i) {
    EXPECT_EQ(got[i].box.x0, want[i].box.x0);
    EXPECT_EQ(got[i].box.y1, want[i].box.y1);
    EXPECT_EQ(got[i].score, want[i].score);
  }
  EXPECT_EQ(src.last_detections().labels.size(), model.forward(img.rgb.data()).labels.size());
}

TEST(Detectron2BoxSource, Errors) {
  shle::DetectorOptions opt;
  opt.labels = {2};
  std::string msg = error_of([&] { shle::Detectron2BoxSource s(random_weights(), opt); });
  EXPECT_NE(msg.find("d2.safetensors: label 2 asked for"), std::string::npos) << msg;
  opt.labels = {};
  opt.score_threshold = 1.0;
  msg = error_of([&] { shle::Detectron2BoxSource s(random_weights(), opt); });
  EXPECT_NE(msg.find("outside [0, 1)"), std::string::npos) << msg;
  // torchvision's weights are another architecture: the first tensor it lacks is named.
  const auto tv = weights::SafeTensors::from_bytes(
      nn::synthetic_weights(det::faster_rcnn_tensor_specs(det::FasterRcnnVariant::MobileNetV3Large320Fpn, 2), 1)
          .bytes(),
      "tv.safetensors");
  msg = error_of([&] { shle::Detectron2BoxSource s(tv); });
  EXPECT_NE(msg.find("tv.safetensors"), std::string::npos) << msg;
  EXPECT_NE(msg.find("missing tensor 'backbone.bottom_up.stem.conv1.weight'"), std::string::npos) << msg;
  // A frame without its image is an error naming the frame.
  shle::Detectron2BoxSource s(random_weights());
  shle::FrameContext frame;
  frame.index = 7;
  EXPECT_NE(error_of([&] { s.candidates(frame); }).find("frame 7"), std::string::npos);
}

}  // namespace
