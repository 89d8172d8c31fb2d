// The synthetic benchmark generator: deterministic, geometrically consistent.
#include <gtest/gtest.h>

#include <cmath>

#include "shle/error.h"
#include "shle/synth.h"

namespace {

shle::synth::SceneSpec spec(std::uint64_t seed, shle::synth::Device d = shle::synth::Device::Bar) {
  shle::synth::SceneSpec s;
  s.seed = seed;
  s.device = d;
  s.frames = 10;
  s.width = 640;
  s.height = 360;
  s.fx = s.fy = 1000;
  s.cx = 320;
  s.cy = 180;
  return s;
}

TEST(Synth, DeterministicPerFrame) {
  shle::synth::Scene a(spec(3)), b(spec(3)), c(spec(4));
  shle::synth::Frame fa = a.render(4), fb = b.render(4), fc = c.render(4);
  EXPECT_EQ(fa.image.rgb, fb.image.rgb);
  EXPECT_EQ(fa.disparity, fb.disparity);
  EXPECT_EQ(fa.detections.size(), fb.detections.size());
  EXPECT_NE(fa.disparity, fc.disparity);
  // Rendering order does not matter.
  shle::synth::Scene d(spec(3));
  d.render(9);
  EXPECT_EQ(d.render(4).disparity, fa.disparity);
}

TEST(Synth, BarGeometryMatchesTruth) {
  shle::synth::SceneSpec s = spec(5);
  s.pitch_noise_deg = 0;
  s.bump_rate = 0;
  s.height_jitter = 0;
  shle::synth::Scene scene(s);
  for (int k : {0, 5, 9}) {
    shle::synth::Frame f = scene.render(k);
    ASSERT_TRUE(f.visible);
    // Level camera: the bar's underside (height 3.3, 0.25 m deep) ends at
    // v = cy - (3.3 - 1.45) f / (Z + 0.25); the box's bottom row is the last above it.
    double v_edge = s.cy - (s.clearance - s.mount_height) * s.fy / (f.distance + 0.25);
    EXPECT_NEAR(f.box.y1, std::floor(v_edge) + 1, 1.0) << k;
    EXPECT_NEAR(0.5 * (f.box.x0 + f.box.x1), s.cx, 2.0);
    // The disparity on the bar's lowest front rows is close to bf / Z.
    int v = static_cast<int>(f.box.y1) - 3;
    int close = 0, total = 0;
    for (int u = static_cast<int>(f.box.x0) + 5; u < static_cast<int>(f.box.x1) - 5; ++u) {
      double d = f.disparity[v * s.width + u] / 32.0;
      double want = s.baseline * s.fx / f.distance;
      ++total;
      close += std::fabs(d - want) < 0.1 * want;
    }
    EXPECT_GT(close, total * 8 / 10) << k;
  }
}

TEST(Synth, DetectorMissesAndDistractors) {
  shle::synth::SceneSpec s = spec(6);
  s.frames = 200;
  s.width = 128;  // detections do not depend on the image size much; keep it fast
  s.height = 72;
  s.fx = s.fy = 200;
  s.cx = 64;
  s.cy = 36;
  s.miss_rate = 0.3;
  s.clutter = false;
  shle::synth::Scene scene(s);
  int visible = 0, hit = 0, distractors = 0;
  for (int k = 0; k < scene.frame_count(); ++k) {
    shle::synth::Frame f = scene.render(k);
    if (!f.visible) continue;
    ++visible;
    for (const shle::Candidate& c : f.detections) {
      bool on_device = std::fabs(c.box.x0 - f.box.x0) < 20 && std::fabs(c.box.y1 - f.box.y1) < 20 && c.score >= 0.55;
      hit += on_device;
      distractors += !on_device;
    }
  }
  ASSERT_GT(visible, 150);
  EXPECT_NEAR(1.0 - double(hit) / visible, 0.3, 0.1);
  EXPECT_GT(distractors, visible / 2);
}

TEST(Synth, EveryDeviceRenders) {
  for (auto d : {shle::synth::Device::Bridge, shle::synth::Device::Cable}) {
    shle::synth::SceneSpec s = spec(7, d);
    s.clearance = d == shle::synth::Device::Bridge ? 5.3 : 4.7;
    shle::synth::Scene scene(s);
    // Thin cables are sub-pixel at 70 m with f = 1000: look from 55 m.
    shle::synth::Frame f = scene.render(2);
    EXPECT_TRUE(f.visible);
    EXPECT_LT(f.box.y1, s.cy);
  }
  EXPECT_EQ(shle::synth::benchmark_scenes().size(), 10u);
}

TEST(Synth, StopsBeforeTheDeviceLeavesTheImage) {
  shle::synth::SceneSpec s = spec(8);
  s.clearance = 6.0;
  shle::synth::Scene scene(s);
  shle::synth::Frame last = scene.render(scene.frame_count() - 1);
  EXPECT_GT(last.distance, 5.0);
  EXPECT_TRUE(last.visible);
}

TEST(Synth, RejectsBadSpecs) {
  shle::synth::SceneSpec s = spec(1);
  s.clearance = 1.0;
  EXPECT_THROW(shle::synth::Scene{s}, shle::Error);
  s = spec(1);
  s.frames = 1;
  EXPECT_THROW(shle::synth::Scene{s}, shle::Error);
  s = spec(1);
  s.end_distance = 80;
  EXPECT_THROW(shle::synth::Scene{s}, shle::Error);
  s = spec(1);
  s.miss_rate = 1.0;
  EXPECT_THROW(shle::synth::Scene{s}, shle::Error);
  EXPECT_THROW(shle::synth::parse_device("tunnel"), shle::Error);
  EXPECT_TRUE(shle::synth::Scene(spec(1)).render(99).image.rgb.empty());
}

}  // namespace
