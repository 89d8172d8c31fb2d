// Bad inputs to the detector: clear errors, never a crash.
#include <gtest/gtest.h>

#include "tests/error_of.h"

#include "nn/error.h"
#include "nn/models/detection/faster_rcnn.h"
#include "nn/models/detection/transform.h"
#include "tests/reference/torch_ref.h"

namespace {

namespace det = nn::detection;

using testutil::error_of;

// Rewrites a weights file with one tensor renamed, dropped or added.
weights::SafeTensors edited(const weights::SafeTensors& st, const std::string& drop, const std::string& add) {
  weights::Writer w;
  for (const auto& name : st.names()) {
    if (name == drop) continue;
    const auto& info = st.info(name);
    w.add(name, info.dtype, info.shape, st.raw(name));
  }
  if (!add.empty()) {
    const float v[2] = {1, 2};
    w.add_f32(add, {2}, v);
  }
  return weights::SafeTensors::from_bytes(w.bytes(), "edited.safetensors");
}

TEST(FasterRcnnErrors, MissingTensorNamed) {
  weights::SafeTensors st = reftest::load_ref("det_mnv3_weights.safetensors");
  const std::string msg = error_of([&] {
    det::FasterRcnn m(edited(st, "backbone.body.4.block.2.fc1.weight", ""), det::FasterRcnnVariant::MobileNetV3LargeFpn);
  });
  EXPECT_NE(msg.find("missing tensor 'backbone.body.4.block.2.fc1.weight'"), std::string::npos) << msg;
}

TEST(FasterRcnnErrors, UnexpectedTensorNamed) {
  weights::SafeTensors st = reftest::load_ref("det_mnv3_weights.safetensors");
  const std::string msg = error_of([&] {
    det::FasterRcnn m(edited(st, "", "backbone.body.layer1.0.conv1.weight"), det::FasterRcnnVariant::MobileNetV3LargeFpn);
  });
  EXPECT_NE(msg.find("unexpected tensor 'backbone.body.layer1.0.conv1.weight'"), std::string::npos) << msg;
}

TEST(FasterRcnnErrors, WrongShapeNamed) {
  weights::SafeTensors st = reftest::load_ref("det_mnv3_weights.safetensors");
  weights::Writer w;
  for (const auto& name : st.names()) {
    const auto& info = st.info(name);
    if (name == "rpn.head.cls_logits.bias") {
      const float v[3] = {0, 0, 0};
      w.add_f32(name, {3}, v);
    } else {
      w.add(name, info.dtype, info.shape, st.raw(name));
    }
  }
  const std::string msg = error_of([&] {
    det::FasterRcnn m(weights::SafeTensors::from_bytes(w.bytes(), "x.safetensors"),
                      det::FasterRcnnVariant::MobileNetV3LargeFpn);
  });
  EXPECT_NE(msg.find("rpn.head.cls_logits.bias"), std::string::npos) << msg;
}

TEST(FasterRcnnErrors, ImageSmallerThan32Pixels) {
  weights::SafeTensors st = reftest::load_ref("det_mnv3_weights.safetensors");
  det::FasterRcnn m(st, det::FasterRcnnVariant::MobileNetV3LargeFpn);
  const std::string msg = error_of([&] { m.plan(31, 640); });
  EXPECT_NE(msg.find("smaller than the minimum 32x32"), std::string::npos) << msg;
  EXPECT_NE(error_of([&] { det::transform_sizes(100, 0, det::TransformConfig{}); }), "");
}

TEST(FasterRcnnErrors, MoreClassesThanTheWeightsHold) {
  weights::SafeTensors st = reftest::load_ref("det_mnv3_weights.safetensors");
  auto cfg = det::faster_rcnn_defaults(det::FasterRcnnVariant::MobileNetV3LargeFpn);
  cfg.roi_heads.num_classes = 5;
  const std::string msg = error_of([&] { det::FasterRcnn m(st, det::FasterRcnnVariant::MobileNetV3LargeFpn, cfg); });
  EXPECT_NE(msg.find("5 classes requested but the weights hold 3"), std::string::npos) << msg;
}

TEST(FasterRcnnErrors, ForwardBeforePlan) {
  weights::SafeTensors st = reftest::load_ref("det_mnv3_weights.safetensors");
  det::FasterRcnn m(st, det::FasterRcnnVariant::MobileNetV3LargeFpn);
  float x[3] = {0, 0, 0};
  EXPECT_NE(error_of([&] { m.forward(x); }), "");
}

}  // namespace
