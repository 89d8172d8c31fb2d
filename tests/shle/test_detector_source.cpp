// The Faster R-CNN box source: the Detections -> candidates conversion (zero-sized
// and inverted boxes dropped, label filter, score threshold), the source on
// seeded random weights against FasterRcnn::forward itself, and its errors.
#include <gtest/gtest.h>

#include "tests/error_of.h"

#include <cmath>
#include <functional>

#include "nn/models/synthetic_weights.h"
#include "shle/detector_box_source.h"
#include "shle/error.h"
#include "tests/shle/test_util.h"

namespace {

namespace det = nn::detection;
constexpr det::FasterRcnnVariant kFast = det::FasterRcnnVariant::MobileNetV3Large320Fpn;

using testutil::error_of;

// Seeded random weights with 3 classes (about 20 M values), made once.
const weights::SafeTensors& random_weights() {
  static const weights::SafeTensors st = weights::SafeTensors::from_bytes(
      nn::synthetic_weights(det::faster_rcnn_tensor_specs(kFast, 3), 5).bytes(), "random.safetensors");
  return st;
}

// The same weights with a predictor for `classes` classes (cheaper than new ones).
weights::SafeTensors with_classes(int classes) {
  const weights::SafeTensors& st = random_weights();
  weights::Writer w;
  for (const std::string& name : st.names()) {
    if (name.rfind("roi_heads.box_predictor.", 0) == 0) continue;
    const weights::TensorInfo& info = st.info(name);
    w.add(name, info.dtype, info.shape, st.raw(name));
  }
  const std::vector<float> zeros(static_cast<std::size_t>(4 * classes) * 1024, 0.0f);
  w.add_f32("roi_heads.box_predictor.cls_score.weight", {classes, 1024}, zeros.data());
  w.add_f32("roi_heads.box_predictor.cls_score.bias", {classes}, zeros.data());
  w.add_f32("roi_heads.box_predictor.bbox_pred.weight", {4 * classes, 1024}, zeros.data());
  w.add_f32("roi_heads.box_predictor.bbox_pred.bias", {4 * classes}, zeros.data());
  return weights::SafeTensors::from_bytes(w.bytes(), "edited.safetensors");
}

// A textured 96x64 image: gradients and a few blocks, so the random network sees detail.
shle::RgbImage test_image(int w, int h) {
  shle::RgbImage img;
  img.width = w;
  img.height = h;
  img.rgb.resize(static_cast<std::size_t>(w) * h * 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      std::uint8_t* p = &img.rgb[(static_cast<std::size_t>(y) * w + x) * 3];
      const bool block = (x / 16 + y / 12) % 3 == 0;
      p[0] = static_cast<std::uint8_t>(block ? 220 : 3 * x % 256);
      p[1] = static_cast<std::uint8_t>(block ? 30 : 4 * y % 256);
      p[2] = static_cast<std::uint8_t>((x * y) % 256);
    }
  return img;
}

det::Detections make_detections() {
  det::Detections d;
  auto add = [&](det::Box b, float s, std::int64_t l) {
    d.boxes.push_back(b);
    d.scores.push_back(s);
    d.labels.push_back(l);
  };
  add({10, 20, 50, 40}, 0.9f, 1);            // 0: kept
  add({10, 20, 10, 40}, 0.9f, 1);            // 1: zero width (clipped at a border)
  add({10, 20, 50, 20}, 0.9f, 1);            // 2: zero height
  add({50, 20, 10, 40}, 0.9f, 1);            // 3: inverted x
  add({10, 40, 50, 20}, 0.9f, 1);            // 4: inverted y
  add({10, 20, NAN, 40}, 0.9f, 1);           // 5: not finite
  add({1, 2, 3, 4}, 0.3f, 1);                // 6: score == threshold: dropped (score > S)
  add({1, 2, 3, 4}, 0.31f, 2);               // 7: label 2
  add({0, 0, 1280, 720}, 0.5f, 0);           // 8: background never counts
  add({5, 6, 7, 9}, 0.95f, 3);               // 9: label 3
  return d;
}

TEST(DetectorCandidates, DropsEmptyBoxesAndFiltersLabelsAndScores) {
  const det::Detections d = make_detections();
  std::vector<shle::Candidate> c = shle::detections_to_candidates(d, {}, 0.3);
  ASSERT_EQ(c.size(), 3u);  // 0, 7, 9: every foreground label
  EXPECT_EQ(c[0].box.x0, 10);
  EXPECT_EQ(c[0].box.y0, 20);
  EXPECT_EQ(c[0].box.x1, 50);
  EXPECT_EQ(c[0].box.y1, 40);
  EXPECT_DOUBLE_EQ(c[0].score, 0.9f);
  EXPECT_DOUBLE_EQ(c[1].score, 0.31f);
  EXPECT_DOUBLE_EQ(c[2].score, 0.95f);
  for (const shle::Candidate& k : c) {
    EXPECT_GT(k.box.width(), 0);
    EXPECT_GT(k.box.height(), 0);
  }
  c = shle::detections_to_candidates(d, {3, 1}, 0.3);
  ASSERT_EQ(c.size(), 2u);
  EXPECT_DOUBLE_EQ(c[1].score, 0.95f);
  c = shle::detections_to_candidates(d, {1}, 0.0);
  ASSERT_EQ(c.size(), 2u);  // 0 and 6
  EXPECT_EQ(c[1].box.x1, 3);
  c = shle::detections_to_candidates(d, {2}, 0.5);
  EXPECT_TRUE(c.empty());
  EXPECT_TRUE(shle::detections_to_candidates(det::Detections{}, {}, 0.3).empty());
}

TEST(DetectorCandidates, ImageToPlanarUnitRange) {
  shle::RgbImage img;
  img.width = 2;
  img.height = 1;
  img.rgb = {0, 51, 255, 255, 102, 1};
  std::vector<float> chw;
  shle::rgb_to_chw01(img, &chw);
  ASSERT_EQ(chw.size(), 6u);
  EXPECT_EQ(chw[0], 0.0f);
  EXPECT_EQ(chw[1], 1.0f);
  EXPECT_EQ(chw[2], 51.0f / 255.0f);
  EXPECT_EQ(chw[3], 102.0f / 255.0f);
  EXPECT_EQ(chw[4], 1.0f);
  EXPECT_EQ(chw[5], 1.0f / 255.0f);
}

// The source gives exactly the model's detections after the filter, and plans
// again when the frame size changes.
TEST(DetectorBoxSource, MatchesFasterRcnnForward) {
  const weights::SafeTensors& st = random_weights();
  shle::DetectorOptions opt;
  opt.score_threshold = 0.3;
  shle::DetectorBoxSource src(st, kFast, opt);
  EXPECT_EQ(src.name(), "detector");
  EXPECT_TRUE(src.needs_image());
  EXPECT_EQ(src.num_classes(), 3);
  EXPECT_EQ(src.labels(), (std::vector<int>{1, 2}));
  det::FasterRcnn model(st, kFast);  // the builder's default score threshold 0.05
  std::size_t total = 0;
  for (auto [w, h] : {std::pair{96, 64}, std::pair{80, 48}, std::pair{96, 64}}) {
    const shle::RgbImage img = test_image(w, h);
    std::vector<shle::Candidate> got = src.candidates(shle::FrameContext{0, nullptr, &img});
    std::vector<float> chw;
    shle::rgb_to_chw01(img, &chw);
    model.plan(h, w);
    const det::Detections ref = model.forward(chw.data());
    const std::vector<shle::Candidate> want = shle::detections_to_candidates(ref, {1, 2}, 0.3);
    ASSERT_EQ(got.size(), want.size()) << w << "x" << h;
    for (std::size_t i = 0; i < got.size(); ++i) {
      EXPECT_EQ(got[i].box.x0, want[i].box.x0);
      EXPECT_EQ(got[i].box.y0, want[i].box.y0);
      EXPECT_EQ(got[i].box.x1, want[i].box.x1);
      EXPECT_EQ(got[i].box.y1, want[i].box.y1);
      EXPECT_EQ(got[i].score, want[i].score);
      EXPECT_GT(got[i].score, 0.3);
      EXPECT_GT(got[i].box.width(), 0);
      EXPECT_GE(got[i].box.x0, 0);
      EXPECT_LE(got[i].box.x1, w);
    }
    total += got.size();
  }
  EXPECT_GT(total, 0u) << "the random weights give no detection above 0.3: the test checks nothing";
  // Only label 2.
  opt.labels = {2};
  shle::DetectorBoxSource only2(st, kFast, opt);
  const shle::RgbImage img = test_image(96, 64);
  model.plan(64, 96);
  std::vector<float> chw;
  shle::rgb_to_chw01(img, &chw);
  EXPECT_EQ(only2.candidates(shle::FrameContext{0, nullptr, &img}).size(),
            shle::detections_to_candidates(model.forward(chw.data()), {2}, 0.3).size());
}

TEST(DetectorBoxSource, LabelBeyondTheWeightsNamesTheClassCount) {
  const weights::SafeTensors& st = random_weights();
  auto error_with = [&](std::vector<int> labels, double score) {
    shle::DetectorOptions opt;
    opt.labels = std::move(labels);
    opt.score_threshold = score;
    return error_of([&] { shle::DetectorBoxSource s(st, kFast, opt); });
  };
  const std::string msg = error_with({1, 3}, 0.3);
  EXPECT_NE(msg.find("random.safetensors: label 3 asked for, but the weights hold 3 classes"), std::string::npos)
      << msg;
  EXPECT_NE(error_with({0}, 0.3).find("background"), std::string::npos);
  EXPECT_NE(error_with({-1}, 0.3).find("label -1"), std::string::npos);
  EXPECT_NE(error_with({}, 1.0).find("outside [0, 1)"), std::string::npos);
  EXPECT_NE(error_with({}, NAN).find("outside [0, 1)"), std::string::npos);
  EXPECT_NE(error_with({}, -0.1).find("outside [0, 1)"), std::string::npos);
}

TEST(DetectorBoxSource, WrongArchitectureNamesFileAndTensor) {
  // MobileNetV3 weights given as ResNet-50: the first ResNet tensor is missing.
  const std::string msg = error_of(
      [&] { shle::DetectorBoxSource s(random_weights(), det::FasterRcnnVariant::ResNet50Fpn); });
  EXPECT_EQ(msg.rfind("random.safetensors: ", 0), 0u) << msg;
  EXPECT_NE(msg.find("missing tensor 'backbone.body."), std::string::npos) << msg;
  // From a file: the path leads the message.
  shletest::TempDir dir;
  const std::string path = dir / "not_a_detector.safetensors";
  const float v[2] = {1, 2};
  weights::Writer w;
  w.add_f32("features.0.0.weight", {2}, v);
  w.write(path);
  const std::string m2 = error_of([&] { shle::DetectorBoxSource s(path, kFast); });
  EXPECT_EQ(m2.rfind(path + ": ", 0), 0u) << m2;
  EXPECT_NE(m2.find("'roi_heads.box_predictor.cls_score.weight'"), std::string::npos) << m2;
  const std::string m3 = error_of([&] { shle::DetectorBoxSource s(dir / "absent.safetensors", kFast); });
  EXPECT_EQ(m3.rfind(dir / "absent.safetensors", 0), 0u) << m3;
}

TEST(DetectorBoxSource, TooSmallOrBrokenImagesAreFrameErrors) {
  shle::DetectorBoxSource src(random_weights(), kFast);
  shle::FrameFiles files;
  files.image = "seq/left/000031.png";
  const shle::RgbImage small = test_image(96, 31);
  std::string msg = error_of([&] { src.candidates(shle::FrameContext{3, &files, &small}); });
  EXPECT_NE(msg.find("seq/left/000031.png: detector input is 31x96, smaller than the minimum 32x32"),
            std::string::npos)
      << msg;
  EXPECT_THROW(src.candidates(shle::FrameContext{3, &files, &small}), shle::Error);
  shle::RgbImage broken = test_image(96, 64);
  broken.rgb.pop_back();
  msg = error_of([&] { src.candidates(shle::FrameContext{3, &files, &broken}); });
  EXPECT_NE(msg.find("does not hold 96x64 RGB pixels"), std::string::npos) << msg;
  EXPECT_NE(error_of([&] { src.candidates(shle::FrameContext{3, &files, nullptr}); }).find("needs the decoded image"),
            std::string::npos);
  // A good frame after the failures still works.
  const shle::RgbImage ok = test_image(96, 64);
  EXPECT_NO_THROW(src.candidates(shle::FrameContext{4, &files, &ok}));
}

TEST(DetectorBoxSource, BackgroundOnlyWeightsAreRejected) {
  const std::string msg = error_of([&] { shle::DetectorBoxSource s(with_classes(1), kFast); });
  EXPECT_NE(msg.find("only the background class"), std::string::npos) << msg;
}

}  // namespace
