// stixel::process_frame on a small synthetic StixelNExT++ (ConvNeXt 8-12-20-28,
// one block per stage, V4 head) at 64x96: the same world and points as the
// pieces called by hand, strided pixels, and bad inputs.
#include <gtest/gtest.h>

#include "tests/strided_image.h"

#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "nn/models/convnext.h"
#include "nn/models/stixel_head.h"
#include "nn/models/synthetic_weights.h"
#include "stixel/error.h"
#include "stixel/frame_pipeline.h"
#include "stixel/stx1.h"

namespace {

constexpr int kH = 64, kW = 96;

std::unique_ptr<stixel::Predictor> make_predictor(stixel::Normalization norm = stixel::Normalization::Raw255) {
  nn::ConvNeXtConfig cfg{{8, 12, 20, 28}, {1, 1, 1, 1}};
  auto specs = nn::convnext_tensor_specs(cfg, "features.");
  for (auto& s : nn::stixel_head_tensor_specs(nn::StixelHeadVariant::V4, 28, "classifier.")) specs.push_back(s);
  const weights::SafeTensors st = weights::SafeTensors::from_bytes(nn::synthetic_weights(specs, 5).bytes(), "synthetic");
  stixel::ModelSettings s;
  s.input_height = kH;
  s.input_width = kW;
  s.normalization = norm;
  return std::make_unique<stixel::Predictor>(st, s);
}

// Contiguous RGB8 pixels with some structure, so the network sees more than noise.
std::vector<std::uint8_t> test_pixels(int w, int h, unsigned seed) {
  std::vector<std::uint8_t> px(static_cast<std::size_t>(w) * h * 3);
  for (std::size_t i = 0; i < px.size(); ++i) px[i] = static_cast<std::uint8_t>((i * (37 + seed) + i / 97) % 251);
  return px;
}

using testutil::with_padding;

stixel::RgbImageView view(const std::vector<std::uint8_t>& px, int w, int h, std::size_t stride = 0) {
  return {px.data(), w, h, stride ? stride : static_cast<std::size_t>(w) * 3};
}

// A standard K for a w x h image (f = 0.8 w) and a camera 1.5 m up, 0.3 m right.
stixel::FrameCamera camera_for(int w, int h, bool with_t) {
  stixel::FrameCamera cam;
  const float f = 0.8f * static_cast<float>(w);
  cam.K = {f, 0, (w - 1) / 2.0f, 0, f * 1.01f, (h - 1) / 2.0f, 0, 0, 1};
  if (with_t) cam.T = {1, 0, 0, -0.3f, 0, 1, 0, 1.5f, 0, 0, 1, 0, 0, 0, 0, 1};
  return cam;
}

void expect_same_points(const std::vector<stixel::Point3>& a, const std::vector<stixel::Point3>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i)
    ASSERT_TRUE(a[i].x == b[i].x && a[i].y == b[i].y && a[i].z == b[i].z) << "point " << i;
}

// Bitwise the same stixels and context (the .stx1 encoding holds every field).
void expect_same_world(const stixel::StixelWorld& a, const stixel::StixelWorld& b) {
  ASSERT_EQ(a.stixels.size(), b.stixels.size());
  for (std::size_t i = 0; i < a.stixels.size(); ++i) {
    const stixel::Stixel &x = a.stixels[i], &y = b.stixels[i];
    ASSERT_TRUE(x.u == y.u && x.vT == y.vT && x.vB == y.vB && x.width == y.width && x.cluster == y.cluster &&
                std::memcmp(&x.d, &y.d, sizeof x.d) == 0 &&
                std::memcmp(&x.confidence, &y.confidence, sizeof x.confidence) == 0)
        << "stixel " << i;
  }
  EXPECT_EQ(a.has_context, b.has_context);
  EXPECT_EQ(a.context.clusters, b.context.clusters);
  EXPECT_EQ(stixel::encode_stx1(a), stixel::encode_stx1(b));
}

// The pipeline as the stixelnext app ran it before process_frame existed.
stixel::FrameResult by_hand(stixel::Predictor& p, const std::vector<std::uint8_t>& px, int w, int h,
                            const stixel::FrameOptions& o) {
  stixel::FrameResult r;
  r.resized = p.preprocess(px.data(), w, h);
  p.run_network();
  std::unique_ptr<stixel::Projection> proj;
  if (o.camera) {
    r.network_K = stixel::scale_intrinsics(o.camera->K, w, h, kW, kH);
    proj = std::make_unique<stixel::Projection>(r.network_K, o.camera->T);
    if (o.train_focal > 0) r.depth_scale = stixel::camera_depth_scale(r.network_K, o.train_focal);
  }
  r.world = p.extract(o.threshold, r.depth_scale);
  r.world.has_context = true;
  if (proj) {
    r.world.context.has_calibration = true;
    auto& c = r.world.context.calibration;
    c.K = r.network_K;
    c.T = o.camera->T;
    c.width = kW;
    c.height = kH;
    c.channels = 3;
    r.top_points = stixel::top_points(r.world, *proj);
    r.bottom_points = stixel::bottom_points(r.world, *proj);
  }
  if (o.cluster) stixel::cluster_stixels(r.world, r.top_points, o.cluster_options);
  return r;
}

class FramePipeline : public testing::Test {
 protected:
  static void SetUpTestSuite() { predictor_ = make_predictor().release(); }
  static void TearDownTestSuite() {
    delete predictor_;
    predictor_ = nullptr;
  }
  static stixel::Predictor* predictor_;
};
stixel::Predictor* FramePipeline::predictor_ = nullptr;

// Network size and another size (resized, K scaled), optical frame and a T,
// plain depths and train_focal, each axis pair: the pieces give the same bits.
TEST_F(FramePipeline, SameWorldAndPointsAsThePiecesByHand) {
  struct Case {
    int w, h;
    bool with_t;
    double threshold, train_focal;
    int axis_a, axis_b;
  };
  const Case cases[] = {{kW, kH, false, 0.0, 0, 0, 2}, {kW, kH, true, 0.36, 90, 0, 1},
                        {70, 50, false, 0.2, 0, 0, 2}, {150, 100, true, 0.0, 60, 2, 0}};
  for (const Case& c : cases) {
    SCOPED_TRACE(std::to_string(c.w) + "x" + std::to_string(c.h));
    const auto px = test_pixels(c.w, c.h, 1);
    stixel::FrameOptions o;
    o.threshold = c.threshold;
    o.train_focal = c.train_focal;
    o.cluster = true;
    o.cluster_options.axis_a = c.axis_a;
    o.cluster_options.axis_b = c.axis_b;
    o.camera = camera_for(c.w, c.h, c.with_t);
    const stixel::FrameResult got = stixel::process_frame(*predictor_, view(px, c.w, c.h), o);
    const stixel::FrameResult want = by_hand(*predictor_, px, c.w, c.h, o);
    ASSERT_FALSE(want.world.stixels.empty());
    expect_same_world(got.world, want.world);
    expect_same_points(got.top_points, want.top_points);
    expect_same_points(got.bottom_points, want.bottom_points);
    EXPECT_EQ(got.top_points.size(), got.world.stixels.size());
    EXPECT_EQ(got.resized, c.w != kW || c.h != kH);
    EXPECT_EQ(got.network_K, want.network_K);
    EXPECT_EQ(got.depth_scale, want.depth_scale);
    if (c.w == kW && c.h == kH) {
      EXPECT_EQ(got.network_K, o.camera->K);
    }
    if (c.train_focal > 0) {
      EXPECT_NE(got.depth_scale, 1.0);
    }
    ASSERT_TRUE(got.projection.has_value());
    const stixel::Projection p(want.network_K, o.camera->T);
    EXPECT_EQ(got.projection->inverse(), p.inverse());
    // The caller's fields stay empty; the rest is the app's context.
    const auto& ctx = got.world.context;
    EXPECT_TRUE(got.world.has_context);
    EXPECT_TRUE(ctx.name.empty());
    EXPECT_TRUE(ctx.has_calibration);
    EXPECT_TRUE(ctx.calibration.img_name.empty());
    EXPECT_EQ(ctx.calibration.K, got.network_K);
    EXPECT_EQ(ctx.calibration.T, o.camera->T);
    EXPECT_EQ(ctx.calibration.width, kW);
    EXPECT_EQ(ctx.calibration.height, kH);
    EXPECT_EQ(ctx.calibration.channels, 3);
    EXPECT_GE(ctx.clusters, -1);
    for (double t : {got.times.preprocess, got.times.network, got.times.extraction, got.times.points,
                     got.times.clustering})
      EXPECT_GE(t, 0.0);
  }
}

TEST_F(FramePipeline, WithoutCameraNoPointsAndNoCalibration) {
  const auto px = test_pixels(kW, kH, 2);
  stixel::FrameOptions o;
  const stixel::FrameResult got = stixel::process_frame(*predictor_, view(px, kW, kH), o);
  const stixel::FrameResult want = by_hand(*predictor_, px, kW, kH, o);
  expect_same_world(got.world, want.world);
  EXPECT_TRUE(got.world.has_context);
  EXPECT_FALSE(got.world.context.has_calibration);
  EXPECT_TRUE(got.world.context.calibration.K.empty());
  EXPECT_TRUE(got.top_points.empty());
  EXPECT_TRUE(got.bottom_points.empty());
  EXPECT_TRUE(got.network_K.empty());
  EXPECT_FALSE(got.projection.has_value());
  EXPECT_FALSE(got.resized);
  EXPECT_EQ(got.depth_scale, 1.0);
  EXPECT_EQ(got.times.points, 0.0);
  EXPECT_EQ(got.times.clustering, 0.0);
}

// points = false: no 3D unless clustering needs the top points.
TEST_F(FramePipeline, PointsOffComputesOnlyWhatClusteringNeeds) {
  const auto px = test_pixels(kW, kH, 3);
  stixel::FrameOptions o;
  o.threshold = 0;
  o.points = false;
  o.camera = camera_for(kW, kH, false);
  stixel::FrameResult r = stixel::process_frame(*predictor_, view(px, kW, kH), o);
  EXPECT_TRUE(r.top_points.empty());
  EXPECT_TRUE(r.bottom_points.empty());
  EXPECT_TRUE(r.projection.has_value());
  EXPECT_TRUE(r.world.context.has_calibration);
  o.cluster = true;
  r = stixel::process_frame(*predictor_, view(px, kW, kH), o);
  EXPECT_EQ(r.top_points.size(), r.world.stixels.size());
  EXPECT_TRUE(r.bottom_points.empty());
  const stixel::FrameResult want = by_hand(*predictor_, px, kW, kH, o);
  expect_same_world(r.world, want.world);
  expect_same_points(r.top_points, want.top_points);
}

// Rows with garbage after them give bitwise the result of contiguous rows, at the
// network size (no resize) and at another size (resized).
TEST_F(FramePipeline, StridedPixelsGiveTheContiguousResult) {
  for (auto [w, h] : {std::pair<int, int>{kW, kH}, {70, 50}}) {
    SCOPED_TRACE(std::to_string(w) + "x" + std::to_string(h));
    const auto px = test_pixels(w, h, 4);
    stixel::FrameOptions o;
    o.threshold = 0.1;
    o.cluster = true;
    o.camera = camera_for(w, h, true);
    const stixel::FrameResult flat = stixel::process_frame(*predictor_, view(px, w, h), o);
    for (std::size_t pad : {1, 13, 64}) {
      const auto padded = with_padding(px, w, h, pad);
      const stixel::FrameResult strided =
          stixel::process_frame(*predictor_, view(padded, w, h, static_cast<std::size_t>(w) * 3 + pad), o);
      expect_same_world(strided.world, flat.world);
      expect_same_points(strided.top_points, flat.top_points);
      expect_same_points(strided.bottom_points, flat.bottom_points);
      EXPECT_EQ(strided.resized, flat.resized);
    }
  }
}

// Predictor::preprocess itself, for every normalisation (ImageNet's per-channel
// constants must follow the pixel, not the buffer offset): the same network output.
TEST(PredictorPreprocess, StrideGivesTheContiguousPrediction) {
  const int planes = 4 * 64 * (kW / 8);
  for (auto norm : {stixel::Normalization::Raw255, stixel::Normalization::Unit, stixel::Normalization::ImageNet}) {
    SCOPED_TRACE(stixel::normalization_name(norm));
    auto p = make_predictor(norm);
    for (auto [w, h] : {std::pair<int, int>{kW, kH}, {41, 33}}) {
      const auto px = test_pixels(w, h, 5);
      const auto padded = with_padding(px, w, h, 7);
      EXPECT_EQ(p->preprocess(px.data(), w, h), w != kW || h != kH);
      const float* out = p->run_network();
      const std::vector<float> flat(out, out + planes);
      EXPECT_EQ(p->preprocess(padded.data(), w, h, static_cast<std::size_t>(w) * 3 + 7), w != kW || h != kH);
      const float* strided = p->run_network();
      EXPECT_EQ(std::memcmp(strided, flat.data(), planes * sizeof(float)), 0);
      // stride == 3 * width is the contiguous call.
      p->preprocess(px.data(), w, h, static_cast<std::size_t>(w) * 3);
      EXPECT_EQ(std::memcmp(p->run_network(), flat.data(), planes * sizeof(float)), 0);
    }
  }
}

// Throws stixel::Error whose one-line message contains `part`.
template <class F>
void expect_error(F&& f, const std::string& part) {
  try {
    f();
    ADD_FAILURE() << "no error; expected one containing '" << part << "'";
  } catch (const stixel::Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(part), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
}

TEST_F(FramePipeline, BadImagesThrow) {
  const auto px = test_pixels(kW, kH, 6);
  const stixel::FrameOptions o;
  auto run = [&](const stixel::RgbImageView& v) { return [&, v] { stixel::process_frame(*predictor_, v, o); }; };
  expect_error(run({nullptr, kW, kH, kW * 3}), "image: null pixel pointer");
  expect_error(run({px.data(), kW, kH, kW * 3 - 1}), "image: row stride 287 bytes is less than 3 * width = 288");
  expect_error(run({px.data(), kW, kH, 0}), "row stride 0 bytes");
  expect_error(run({px.data(), 0, kH, kW * 3}), "image: size 0x64 is empty");
  expect_error(run({px.data(), kW, 0, kW * 3}), "image: size 96x0 is empty");
  expect_error(run({px.data(), -5, kH, kW * 3}), "is empty");
  expect_error([&] { predictor_->preprocess(nullptr, kW, kH); }, "null pixel pointer");
  expect_error([&] { predictor_->preprocess(px.data(), 0, 0); }, "is empty");
}

TEST_F(FramePipeline, BadCamerasAndOptionsThrow) {
  const auto px = test_pixels(kW, kH, 7);
  auto run_with = [&](const stixel::FrameOptions& o) {
    return [&, o] { stixel::process_frame(*predictor_, view(px, kW, kH), o); };
  };
  auto with_camera = [&](std::vector<float> K, std::vector<float> T = {}) {
    stixel::FrameOptions o;
    o.camera = stixel::FrameCamera{std::move(K), std::move(T), "cam.json"};
    return o;
  };
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  expect_error(run_with(with_camera({0, 0, 0, 0, 0, 0, 0, 0, 1})), "cam.json: K4 * T is singular");
  expect_error(run_with(with_camera({80, 0, 47.5f, 160, 0, 95, 0, 0, 1})), "singular");  // rank 2
  expect_error(run_with(with_camera({80, 0, nan, 0, 80, 31.5f, 0, 0, 1})), "cam.json: K[2] is not finite");
  expect_error(run_with(with_camera({inf, 0, 47.5f, 0, 80, 31.5f, 0, 0, 1})), "cam.json: K[0] is not finite");
  expect_error(run_with(with_camera({80, 0, 47.5f, 0, 80, 31.5f, 0, 0})), "cam.json: K has 8 values, expected 9");
  expect_error(run_with(with_camera(camera_for(kW, kH, false).K, std::vector<float>(15, 1.0f))),
               "cam.json: T has 15 values, expected 16");
  expect_error(run_with(with_camera(camera_for(kW, kH, false).K, std::vector<float>(16, 0.0f))), "singular");
  stixel::FrameCamera unnamed = camera_for(kW, kH, false);
  unnamed.K[4] = nan;
  stixel::FrameOptions o;
  o.camera = unnamed;
  expect_error(run_with(o), "camera: K[4] is not finite");

  o = {};
  o.cluster = true;
  expect_error(run_with(o), "clustering needs a camera");
  o = {};
  o.train_focal = 100;
  expect_error(run_with(o), "depth scaling needs a camera");
  o = with_camera(camera_for(kW, kH, false).K);
  o.train_focal = -1;
  expect_error(run_with(o), "train focal length must be positive");
  o.train_focal = std::nan("");
  expect_error(run_with(o), "train focal length must be positive");
  o.train_focal = 0;
  o.threshold = 1.5;
  expect_error(run_with(o), "threshold must be in [0, 1]");
  o.threshold = std::nan("");
  expect_error(run_with(o), "threshold must be in [0, 1]");
  o.threshold = 0.36;
  o.cluster = true;
  o.cluster_options.axis_b = 0;
  expect_error(run_with(o), "clustering: axes must be two different");
  o.cluster_options.axis_b = 2;
  o.cluster_options.eps = 0;
  expect_error(run_with(o), "clustering: eps must be positive");
  o.cluster_options.eps = 1.42;
  o.cluster_options.min_samples = 0;
  expect_error(run_with(o), "clustering: min_samples must be >= 1");
}

}  // namespace
