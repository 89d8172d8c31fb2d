// detectron2's Faster R-CNN R50-FPN end to end against the torch/numpy reference
// written from shared/reference/detectron2.md (detectron2_ref.py), at 720x1280
// (upscaled to 750x1333), 1080x1920 (antialiased downscale to 750x1333) and 500x740
// (800x1184, odd P5 and P6): the Pillow resize bitwise, proposals and detections
// matched both ways. The weights are the reference's trainer checkpoint
// (model_final.pth) as weights/export.py converts it.
#include <gtest/gtest.h>

#include <cstring>

#include "nn/error.h"
#include "nn/models/detection/detectron2_faster_rcnn.h"
#include "nn/models/synthetic_weights.h"
#include "nn/threads.h"
#include "tests/detection/match.h"
#include "tests/error_of.h"
#include "tests/reference/torch_ref.h"

namespace {

namespace det = nn::detection;
using testutil::error_of;

std::vector<std::uint8_t> u8(const weights::SafeTensors& st, const std::string& name) {
  const auto& info = st.info(name);
  std::size_t n = 1;
  for (auto d : info.shape) n *= static_cast<std::size_t>(d);
  const std::uint8_t* p = st.raw(name);
  return std::vector<std::uint8_t>(p, p + n);
}

// "small" (180x240 at MIN_SIZE_TEST 240, MAX_SIZE_TEST 320, recorded in the case file)
// is the one case of ROADNN_TEST_SIZES=small; the others are large inputs.
void check_case(const std::string& case_name) {
  if (case_name != "small") {
    ROADNN_SKIP_LARGE_INPUT();
  }
  weights::SafeTensors w = reftest::load_ref("d2_weights.safetensors");
  weights::SafeTensors c = reftest::load_ref("d2_" + case_name + ".safetensors");
  det::Detectron2FasterRcnnConfig cfg;
  if (c.has("transform_size")) {
    const auto sizes = c.i64("transform_size");
    ASSERT_EQ(sizes.size(), 2u);
    cfg.transform.min_size = static_cast<int>(sizes[0]);
    cfg.transform.max_size = static_cast<int>(sizes[1]);
  }
  det::Detectron2FasterRcnn model(w, cfg);
  EXPECT_EQ(model.num_classes(), 2);
  const auto& in_shape = c.info("input").shape;
  const int h = static_cast<int>(in_shape[0]), wd = static_cast<int>(in_shape[1]);
  model.plan(h, wd);
  const auto rgb = u8(c, "input");
  const det::Detections det = model.forward(rgb.data());
  const std::string what = "detectron2/" + case_name;

  // The Pillow resize: bitwise.
  const auto& rs = c.info("resized").shape;
  ASSERT_EQ(rs, (std::vector<std::int64_t>{model.sizes().resized_h, model.sizes().resized_w, 3})) << what;
  EXPECT_TRUE(u8(c, "resized") == model.resized()) << what << ": resized image differs from Pillow's";

  // Proposals (logits as scores) and detections: >= 95 % matched both ways at IoU >=
  // 0.99 with scores within 1e-3; the counts are printed for the log.
  const auto ref_props = dettest::to_boxes(c.f32("proposals"));
  const auto ref_logits = c.f32("proposal_logits");
  const auto& props = model.proposals();
  ASSERT_GE(ref_props.size(), 100u) << what << ": the reference should exercise real proposals";
  auto a = dettest::match(ref_props, ref_logits, {}, props.boxes, props.scores, {}, 0.99, 1e-3);
  auto b = dettest::match(props.boxes, props.scores, {}, ref_props, ref_logits, {}, 0.99, 1e-3);
  std::printf("%s: proposals reference %zu ours %zu, matched %zu/%zu and %zu/%zu\n", what.c_str(), ref_props.size(),
              props.boxes.size(), a.matched, a.total, b.matched, b.total);
  EXPECT_GE(a.fraction(), 0.95) << what << " reference proposals unmatched:" << a.unmatched;
  EXPECT_GE(b.fraction(), 0.95) << what << " our proposals unmatched:" << b.unmatched;

  const auto ref_boxes = dettest::to_boxes(c.f32("boxes"));
  const auto ref_scores = c.f32("scores");
  const auto ref_classes = c.i64("classes");
  ASSERT_GT(ref_boxes.size(), 10u) << what << ": the reference should exercise real detections";
  auto d1 = dettest::match(ref_boxes, ref_scores, ref_classes, det.boxes, det.scores, det.labels, 0.99, 1e-3);
  auto d2 = dettest::match(det.boxes, det.scores, det.labels, ref_boxes, ref_scores, ref_classes, 0.99, 1e-3);
  std::printf("%s: detections reference %zu ours %zu, matched %zu/%zu and %zu/%zu\n", what.c_str(),
              ref_boxes.size(), det.boxes.size(), d1.matched, d1.total, d2.matched, d2.total);
  if (!d1.unmatched.empty()) std::printf("  reference detections unmatched:%s\n", d1.unmatched.c_str());
  if (!d2.unmatched.empty()) std::printf("  our detections unmatched:%s\n", d2.unmatched.c_str());
  EXPECT_GE(d1.fraction(), 0.95) << what;
  EXPECT_GE(d2.fraction(), 0.95) << what;
  // Boxes lie in the original image; classes are 0-based foreground classes.
  for (std::size_t i = 0; i < det.boxes.size(); ++i) {
    const auto& bx = det.boxes[i];
    EXPECT_TRUE(bx.x1 >= 0 && bx.y1 >= 0 && bx.x2 <= wd && bx.y2 <= h && bx.x2 > bx.x1 && bx.y2 > bx.y1) << what;
    EXPECT_TRUE(det.labels[i] >= 0 && det.labels[i] < 2) << what;
  }
}

TEST(Detectron2Torch, Upscale720p) { check_case("720p"); }
TEST(Detectron2Torch, AntialiasedDownscale1080p) { check_case("1080p"); }
TEST(Detectron2Torch, OddPyramid500x740) { check_case("odd"); }
TEST(Detectron2Torch, Small180x240) { check_case("small"); }

// The model zoo's pickled numpy checkpoint converts to the same tensors as the
// trainer's model_final.pth.
TEST(Detectron2Torch, PickledNumpyCheckpointConvertsTheSame) {
  weights::SafeTensors a = reftest::load_ref("d2_weights.safetensors");
  weights::SafeTensors b = reftest::load_ref("d2_weights_from_pkl.safetensors");
  ASSERT_EQ(a.names(), b.names());
  EXPECT_EQ(a.names().size(), 295u);
  for (const auto& n : a.names()) EXPECT_EQ(a.f32(n), b.f32(n)) << n;
}

// Bitwise the same detections for 1 and 2 threads (at a smaller input size: the
// split of the work, not the size, is what is tested).
TEST(Detectron2Torch, DeterministicAcrossThreadCounts) {
  ROADNN_SKIP_IN_SMALL_RUN("two detector passes with 1000 proposals; the NEON kernels' thread-count independence "
                           "is checked by the GEMM split test and the ConvNeXt and StixelNExT++ determinism tests");
  weights::SafeTensors w = reftest::load_ref("d2_weights.safetensors");
  const bool small = reftest::small_sizes_only();
  weights::SafeTensors c = reftest::load_ref(small ? "d2_small.safetensors" : "d2_odd.safetensors");
  det::Detectron2FasterRcnnConfig cfg;
  cfg.transform.min_size = small ? 240 : 400, cfg.transform.max_size = small ? 320 : 667;
  det::Detectron2FasterRcnn model(w, cfg);
  const auto& s = c.info("input").shape;
  model.plan(static_cast<int>(s[0]), static_cast<int>(s[1]));
  const auto rgb = u8(c, "input");
  nn::set_num_threads(1);
  const auto one = model.forward(rgb.data());
  nn::set_num_threads(2);
  const auto two = model.forward(rgb.data());
  nn::set_num_threads(0);
  ASSERT_GT(one.boxes.size(), 0u);
  EXPECT_TRUE(dettest::identical(one, two));
}

}  // namespace

// Weights problems are one clear message naming the tensor.
namespace {

// Seeded random weights for K = 2 (made once), or a copy without `drop`, with an
// `extra` tensor, or with cls_score for `classes` rows.
weights::SafeTensors synthetic(const std::string& drop = "", const std::string& extra = "", int classes = 3) {
  static const weights::SafeTensors base = weights::SafeTensors::from_bytes(
      nn::synthetic_weights(det::detectron2_faster_rcnn_tensor_specs(3), 3).bytes(), "w.safetensors");
  if (drop.empty() && extra.empty() && classes == 3) return base;
  weights::Writer w;
  for (const std::string& name : base.names()) {
    if (name == drop) continue;
    const weights::TensorInfo& info = base.info(name);
    if (name.rfind("roi_heads.box_predictor.cls_score.", 0) == 0 && classes != 3) {
      std::vector<std::int64_t> shape = info.shape;
      shape[0] = classes;
      const std::vector<float> v(static_cast<std::size_t>(classes) * (shape.size() > 1 ? shape[1] : 1), 0.5f);
      w.add_f32(name, shape, v.data());
      continue;
    }
    w.add(name, info.dtype, info.shape, base.raw(name));
  }
  if (!extra.empty()) {
    const float v[4] = {};
    w.add_f32(extra, {4}, v);
  }
  return weights::SafeTensors::from_bytes(w.bytes(), "w.safetensors");
}

TEST(Detectron2Errors, CheckpointHas295Tensors) {
  EXPECT_EQ(det::detectron2_faster_rcnn_tensor_specs(2).size(), 295u);
  EXPECT_EQ(det::detectron2_faster_rcnn_tensor_specs(2)[0].name, "backbone.bottom_up.stem.conv1.weight");
}

// One test (one process, one set of random weights): missing, extra and misshapen
// tensors, a score layer without the background row, and inputs the model refuses.
TEST(Detectron2Errors, WeightsAndInputProblemsAreNamed) {
  std::string msg = error_of([] { det::Detectron2FasterRcnn m(synthetic("backbone.bottom_up.res3.0.conv1.norm.running_var")); });
  EXPECT_NE(msg.find("w.safetensors"), std::string::npos) << msg;
  EXPECT_NE(msg.find("backbone.bottom_up.res3.0.conv1.norm.running_var"), std::string::npos) << msg;
  msg = error_of([] { det::Detectron2FasterRcnn m(synthetic("", "backbone.body.conv1.weight")); });
  EXPECT_NE(msg.find("unexpected tensor 'backbone.body.conv1.weight'"), std::string::npos) << msg;
  // One score row: no room for the background.
  msg = error_of([] { det::Detectron2FasterRcnn m(synthetic("", "", 1)); });
  EXPECT_NE(msg.find("cls_score"), std::string::npos) << msg;
  // K + 1 rows must match bbox_pred's 4K.
  msg = error_of([] { det::Detectron2FasterRcnn m(synthetic("", "", 4)); });
  EXPECT_NE(msg.find("roi_heads.box_predictor.bbox_pred.weight"), std::string::npos) << msg;
  det::Detectron2FasterRcnn m(synthetic());
  EXPECT_NE(error_of([&] { std::uint8_t px[3] = {}; m.forward(px); }).find("before plan"), std::string::npos);
  EXPECT_NE(error_of([&] { m.plan(20, 640); }).find("smaller than the minimum"), std::string::npos);
  EXPECT_NE(error_of([&] { m.plan(640, 20001); }).find("larger than 20000"), std::string::npos);
}

}  // namespace

namespace {

// An older checkpoint's pixel_mean / pixel_std replace the configured normalisation.
TEST(Detectron2Errors, CheckpointPixelStatisticsAreUsed) {
  const weights::SafeTensors base = synthetic();
  weights::Writer w;
  for (const std::string& name : base.names()) w.add(name, base.info(name).dtype, base.info(name).shape, base.raw(name));
  const float mean[3] = {1, 2, 3}, std[3] = {2, 4, 8};
  w.add_f32("pixel_mean", {3, 1, 1}, mean);
  w.add_f32("pixel_std", {3, 1, 1}, std);
  det::Detectron2FasterRcnnConfig cfg;
  cfg.transform.min_size = cfg.transform.max_size = 64;  // a small, quick forward
  det::Detectron2FasterRcnn m(weights::SafeTensors::from_bytes(w.bytes(), "old.safetensors"), cfg);
  m.plan(40, 40);
  std::vector<std::uint8_t> rgb(40 * 40 * 3);
  for (std::size_t i = 0; i < rgb.size(); i += 3) rgb[i] = 10, rgb[i + 1] = 20, rgb[i + 2] = 30;
  m.forward(rgb.data());
  const float* px = m.transformed().data;  // B, G, R of pixel (0, 0)
  EXPECT_EQ(px[0], (30.0f - 1.0f) / 2.0f);
  EXPECT_EQ(px[1], (20.0f - 2.0f) / 4.0f);
  EXPECT_EQ(px[2], (10.0f - 3.0f) / 8.0f);
  // A wrong shape is refused by name.
  weights::Writer bad;
  for (const std::string& name : base.names())
    bad.add(name, base.info(name).dtype, base.info(name).shape, base.raw(name));
  bad.add_f32("pixel_mean", {3}, mean);
  const std::string msg =
      error_of([&] { det::Detectron2FasterRcnn b(weights::SafeTensors::from_bytes(bad.bytes(), "bad.safetensors")); });
  EXPECT_NE(msg.find("pixel_mean"), std::string::npos) << msg;
}

}  // namespace
