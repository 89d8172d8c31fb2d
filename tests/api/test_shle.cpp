// The streaming SHLE entry points (roadnn_shle_*): misuse of each, and the heights
// they give equal shle::StreamEstimator's on the same frames, bit for bit.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "shle/stream.h"
#include "tests/api/api_util.h"

namespace apitest {
namespace {

constexpr int kW = 320, kH = 180;

// A level road seen from 1.45 m and a bar `bar` m above it at depth z (as
// examples/shle_stream.c draws it), with the bar's box.
struct Frame {
  std::vector<float> disparity;
  roadnn_box box;
};

Frame make_frame(const roadnn_shle_params& p, double z, double bar) {
  Frame f;
  f.disparity.assign(static_cast<std::size_t>(kW) * kH, 0.0f);
  const double v_bar = p.cy - (bar - p.mount_height) * p.fy / z;
  for (int v = 0; v < kH; ++v)
    for (int u = 0; u < kW; ++u) {
      float d = 0;
      if (v > p.cy + 2) d = static_cast<float>(p.bf * (v - p.cy) / (p.fy * p.mount_height));
      if (v >= v_bar - 8 && v <= v_bar && u >= 100 && u < 220) d = static_cast<float>(p.bf / z);
      f.disparity[static_cast<std::size_t>(v) * kW + u] = d;
    }
  f.box = {100, v_bar - 8, 220, v_bar, 0.9};
  return f;
}

roadnn_shle_params shle_params() {
  roadnn_shle_params p = roadnn_shle_default_params();
  p.width = kW, p.height = kH;
  p.fx = p.fy = 250, p.cx = 160, p.cy = 90;
  p.bf = 0.3 * 250;
  p.tracker = "none";
  return p;
}

struct ShlePtr {
  roadnn_shle* p = nullptr;
  ~ShlePtr() { roadnn_shle_free(p); }
};

TEST(ApiShle, DefaultsAreTheReleasedCodes) {
  const roadnn_shle_params p = roadnn_shle_default_params();
  const shle::PipelineOptions o;
  EXPECT_EQ(p.extend_top, o.height.extend_top);
  EXPECT_EQ(p.min_height, o.height.min_height);
  EXPECT_EQ(p.bandwidth, o.height.bandwidth);
  EXPECT_EQ(p.lowest_n, o.height.lowest_n);
  EXPECT_EQ(p.min_score, o.box_rule.min_score);
  EXPECT_EQ(p.kalman_q, o.temporal.kalman.q);
  EXPECT_EQ(p.use_kalman, 1);
  EXPECT_STREQ(p.tracker, "ncc");
  EXPECT_EQ(p.fx, 0.0);  // required: create fails without it
}

TEST(ApiShle, CreateMisuse) {
  roadnn_shle* h = reinterpret_cast<roadnn_shle*>(1);
  const roadnn_shle_params good = shle_params();
  EXPECT_API_ERROR(roadnn_shle_create(nullptr, nullptr, 0, &h), ROADNN_ERROR_INVALID_ARGUMENT, "params is null");
  EXPECT_EQ(h, nullptr);
  EXPECT_API_ERROR(roadnn_shle_create(&good, nullptr, 0, nullptr), ROADNN_ERROR_INVALID_ARGUMENT, "out is null");
  EXPECT_API_ERROR(roadnn_shle_create(&good, nullptr, -1, &h), ROADNN_ERROR_INVALID_ARGUMENT, "threads");
  auto bad = [&](auto change, const char* part) {
    roadnn_shle_params p = good;
    change(p);
    roadnn_shle* out = reinterpret_cast<roadnn_shle*>(1);
    EXPECT_API_ERROR(roadnn_shle_create(&p, nullptr, 0, &out), ROADNN_ERROR_INVALID_ARGUMENT, part);
    EXPECT_EQ(out, nullptr) << part;
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  bad([](roadnn_shle_params& p) { p.width = 10; }, "width and height");
  bad([](roadnn_shle_params& p) { p.fx = 0; }, "fx and fy");
  bad([&](roadnn_shle_params& p) { p.fy = nan; }, "fx and fy");
  bad([&](roadnn_shle_params& p) { p.cx = nan; }, "cx and cy");
  bad([&](roadnn_shle_params& p) { p.bf = nan; }, "bf");
  bad([](roadnn_shle_params& p) { p.bf = -1; }, "bf");
  bad([](roadnn_shle_params& p) { p.widest_rule = 2; }, "widest_rule");
  bad([](roadnn_shle_params& p) { p.min_score = 1; }, "min_score");
  bad([](roadnn_shle_params& p) { p.use_kalman = 3; }, "use_kalman");
  bad([](roadnn_shle_params& p) { p.kalman_q = 0; }, "kalman_q");
  bad([&](roadnn_shle_params& p) { p.kalman_r = nan; }, "kalman_q");
  bad([](roadnn_shle_params& p) { p.max_track_frames = -1; }, "max_track_frames");
  bad([](roadnn_shle_params& p) { p.tracker = "kcf"; }, "kcf");
  bad([](roadnn_shle_params& p) { p.lowest_n = 0; }, "");
  // A detector that is not a detector.
  const ModelPtr convnext = load_convnext();
  EXPECT_API_ERROR(roadnn_shle_create(&good, convnext.get(), 0, &h), ROADNN_ERROR_WRONG_MODEL, "Faster R-CNN");
  EXPECT_EQ(h, nullptr);
  roadnn_shle_free(nullptr);  // a no-op
  EXPECT_API_ERROR(roadnn_shle_reset(nullptr), ROADNN_ERROR_INVALID_ARGUMENT, "shle is null");
}

TEST(ApiShle, PushMisuse) {
  const roadnn_shle_params p = shle_params();
  ShlePtr h;
  ASSERT_EQ(ROADNN_OK, roadnn_shle_create(&p, nullptr, 0, &h.p)) << roadnn_last_error();
  const Frame f = make_frame(p, 15, 3.3);
  roadnn_shle_frame out;
  const float* d = f.disparity.data();
  EXPECT_API_ERROR(roadnn_shle_push(nullptr, d, kW, kH, &f.box, 1, nullptr, &out), ROADNN_ERROR_INVALID_ARGUMENT,
                   "shle is null");
  EXPECT_API_ERROR(roadnn_shle_push(h.p, nullptr, kW, kH, &f.box, 1, nullptr, &out), ROADNN_ERROR_INVALID_ARGUMENT,
                   "disparity is null");
  EXPECT_API_ERROR(roadnn_shle_push(h.p, d, kW, kH, &f.box, 1, nullptr, nullptr), ROADNN_ERROR_INVALID_ARGUMENT,
                   "out is null");
  EXPECT_API_ERROR(roadnn_shle_push(h.p, d, kW - 1, kH, &f.box, 1, nullptr, &out), ROADNN_ERROR_INVALID_ARGUMENT,
                   "but the frames are 320x180");
  EXPECT_API_ERROR(roadnn_shle_push(h.p, d, kW, kH, nullptr, 1, nullptr, &out), ROADNN_ERROR_INVALID_ARGUMENT,
                   "boxes is null");
  std::vector<std::uint8_t> rgb(static_cast<std::size_t>(kW) * kH * 3, 128);
  const roadnn_image small{rgb.data(), kW / 2, kH, 0};
  EXPECT_API_ERROR(roadnn_shle_push(h.p, d, kW, kH, &f.box, 1, &small, &out), ROADNN_ERROR_INVALID_ARGUMENT,
                   "the left image is 160x180");
  const roadnn_image strided{rgb.data(), kW / 2, kH, 10};
  EXPECT_API_ERROR(roadnn_shle_push(h.p, d, kW, kH, &f.box, 1, &strided, &out), ROADNN_ERROR_INVALID_ARGUMENT,
                   "stride");
  // Bad frames are not errors: the frame gets no height and says why.
  const roadnn_box nan_box{std::nan(""), 1, 2, 3, 0.9};
  ASSERT_EQ(ROADNN_OK, roadnn_shle_push(h.p, d, kW, kH, &nan_box, 1, nullptr, &out)) << roadnn_last_error();
  EXPECT_FALSE(out.has_height);
  EXPECT_TRUE(is_one_line(out.problem)) << out.problem;
  // The estimator still works afterwards.
  ASSERT_EQ(ROADNN_OK, roadnn_shle_push(h.p, d, kW, kH, &f.box, 1, nullptr, &out)) << roadnn_last_error();
  EXPECT_TRUE(out.has_height) << out.problem;
  EXPECT_NEAR(out.height, 3.3, 0.1);
  EXPECT_STREQ(out.problem, "");

  // With a detector: it finds the boxes, so none may be passed, and it needs the image.
  ShlePtr hd;
  ASSERT_EQ(ROADNN_OK, roadnn_shle_create(&p, shared_detector(), 1, &hd.p)) << roadnn_last_error();
  EXPECT_API_ERROR(roadnn_shle_push(hd.p, d, kW, kH, &f.box, 1, nullptr, &out), ROADNN_ERROR_INVALID_ARGUMENT,
                   "pass no boxes");
  EXPECT_API_ERROR(roadnn_shle_push(hd.p, d, kW, kH, nullptr, 0, nullptr, &out), ROADNN_ERROR_INVALID_ARGUMENT,
                   "needs the left image");
  const roadnn_image left{rgb.data(), kW, kH, 0};
  EXPECT_EQ(ROADNN_OK, roadnn_shle_push(hd.p, d, kW, kH, nullptr, 0, &left, &out)) << roadnn_last_error();
  EXPECT_EQ(out.index, 0);
}

// The C API adds nothing to the engine's arithmetic: its heights, filtered heights and
// scene means are shle::StreamEstimator's, bit for bit; reset() starts over.
TEST(ApiShle, EqualsTheStreamEstimator) {
  for (int kalman : {1, 0}) {
    roadnn_shle_params p = shle_params();
    p.use_kalman = kalman;
    ShlePtr h;
    ASSERT_EQ(ROADNN_OK, roadnn_shle_create(&p, nullptr, 0, &h.p)) << roadnn_last_error();
    shle::Calibration cal;
    cal.intrinsics = {p.fx, p.fy, p.cx, p.cy};
    cal.bf = p.bf;
    cal.mount_height = p.mount_height;
    cal.width = kW, cal.height = kH;
    shle::PipelineOptions o;
    o.tracker = "none";
    o.temporal.use_kalman = kalman == 1;
    shle::StreamEstimator ref(cal, o);
    std::vector<double> first_pass;
    int heights = 0;
    for (int pass = 0; pass < 2; ++pass) {
      for (int i = 0; i < 6; ++i) {
        const Frame f = make_frame(p, 18.0 + i, 3.3);
        roadnn_shle_frame got;
        ASSERT_EQ(ROADNN_OK, roadnn_shle_push(h.p, f.disparity.data(), kW, kH, &f.box, 1, nullptr, &got))
            << roadnn_last_error();
        shle::DisparityMap dm{kW, kH, f.disparity};
        shle::StreamInput in;
        in.disparity = &dm;
        in.candidates.push_back({{f.box.x0, f.box.y0, f.box.x1, f.box.y1}, f.box.score});
        const shle::StreamFrame want = ref.push(in);
        EXPECT_EQ(got.index, i);
        heights += got.has_height;
        EXPECT_EQ(got.has_height, want.stage2.has_height ? 1 : 0);
        EXPECT_EQ(got.height, want.stage2.height) << i;
        EXPECT_EQ(got.filtered, want.filtered) << i;
        EXPECT_EQ(got.scene_height, want.scene_height) << i;
        if (pass == 0) {
          first_pass.push_back(got.scene_height);
        } else {
          EXPECT_EQ(got.scene_height, first_pass[i]) << "after reset, frame " << i;
        }
      }
      ASSERT_EQ(ROADNN_OK, roadnn_shle_reset(h.p));
      ref.reset();
    }
    EXPECT_GE(heights, 6) << "the scene should give most frames a height";
    if (kalman) {
      EXPECT_NE(first_pass.front(), first_pass.back());
    }
  }
}

}  // namespace
}  // namespace apitest
