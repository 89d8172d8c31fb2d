// The NCC tracker on rendered, textured frames: known shifts are recovered exactly.
#include <gtest/gtest.h>

#include <cmath>

#include "shle/metrics.h"
#include "shle/synth.h"
#include "shle/tracker.h"

namespace {

struct Rendered {
  shle::GrayImage gray, next;
  shle::Box box, next_box;
};

const Rendered& rendered() {
  static const Rendered r = [] {
    shle::synth::SceneSpec s;
    s.seed = 21;
    s.frames = 20;
    s.start_distance = 40;
    s.end_distance = 20;
    s.width = 640;
    s.height = 360;
    s.fx = s.fy = 1000;
    s.cx = 320;
    s.cy = 180;
    shle::synth::Scene scene(s);
    shle::synth::Frame a = scene.render(5), b = scene.render(6);
    Rendered out;
    out.gray = shle::to_gray(a.image);
    out.next = shle::to_gray(b.image);
    out.box = a.box;
    out.next_box = b.box;
    return out;
  }();
  return r;
}

// Content moved by (dx, dy); borders replicate the edge.
shle::GrayImage shifted(const shle::GrayImage& g, int dx, int dy) {
  shle::GrayImage s = g;
  for (int y = 0; y < g.height; ++y)
    for (int x = 0; x < g.width; ++x) {
      int sx = std::min(std::max(x - dx, 0), g.width - 1), sy = std::min(std::max(y - dy, 0), g.height - 1);
      s.px[y * g.width + x] = g.px[sy * g.width + sx];
    }
  return s;
}

TEST(NccTracker, RecoversKnownShifts) {
  const Rendered& r = rendered();
  ASSERT_GT(r.box.width(), 20);
  const double x = std::trunc(r.box.x0), y = std::trunc(r.box.y0);
  const double w = std::trunc(r.box.x1 - r.box.x0), h = std::trunc(r.box.y1 - r.box.y0);
  const int shifts[][2] = {{0, 0}, {7, -3}, {-15, 10}, {24, 0}, {0, -24}, {17, 17}, {-1, 1}, {-20, -14}};
  for (const auto& s : shifts) {
    shle::NccTracker t;
    ASSERT_TRUE(t.init(shle::view(r.gray), r.box));
    shle::GrayImage moved = shifted(r.gray, s[0], s[1]);
    shle::Box b;
    ASSERT_TRUE(t.update(shle::view(moved), &b)) << s[0] << "," << s[1];
    EXPECT_EQ(b.x0, x + s[0]) << s[0] << "," << s[1];
    EXPECT_EQ(b.y0, y + s[1]) << s[0] << "," << s[1];
    EXPECT_EQ(b.width(), w);
    EXPECT_EQ(b.height(), h);
    EXPECT_NEAR(t.last_score(), 1.0, 1e-9);
  }
}

TEST(NccTracker, FollowsASequenceOfShifts) {
  // Successive updates start from the last position: total shift beyond one radius.
  const Rendered& r = rendered();
  shle::NccTracker t;
  ASSERT_TRUE(t.init(shle::view(r.gray), r.box));
  shle::Box b;
  for (int k = 1; k <= 3; ++k) {
    ASSERT_TRUE(t.update(shle::view(shifted(r.gray, 20 * k, 0)), &b));
    EXPECT_EQ(b.x0, std::trunc(r.box.x0) + 20 * k);
  }
}

TEST(NccTracker, SearchRadiusLimitsTheMove) {
  const Rendered& r = rendered();
  shle::NccOptions o;
  o.search_radius = 10;
  shle::NccTracker t(o);
  ASSERT_TRUE(t.init(shle::view(r.gray), r.box));
  shle::Box b;
  ASSERT_TRUE(t.update(shle::view(shifted(r.gray, 15, 0)), &b));
  double dx = b.x0 - std::trunc(r.box.x0), dy = b.y0 - std::trunc(r.box.y0);
  EXPECT_LT(dx * dx + dy * dy, 100.0);
  EXPECT_LT(t.last_score(), 1.0);
}

TEST(NccTracker, TracksTheNextRenderedFrame) {
  // The camera moves 1 m closer: the device grows a little, the fixed-size box
  // must stay on it.
  const Rendered& r = rendered();
  shle::NccTracker t;
  ASSERT_TRUE(t.init(shle::view(r.gray), r.box));
  shle::Box b;
  ASSERT_TRUE(t.update(shle::view(r.next), &b));
  shle::CentreDistance c;
  ASSERT_TRUE(shle::centre_distance(b, r.next_box, &c));
  EXPECT_LT(c.cpd, 6.0);
}

TEST(NccTracker, RefusesWhatCannotBeTracked) {
  shle::GrayImage flat;
  flat.width = 64;
  flat.height = 48;
  flat.px.assign(64 * 48, 128);
  shle::NccTracker t;
  shle::Box b;
  EXPECT_FALSE(t.update(shle::view(flat), &b));  // not seeded
  EXPECT_FALSE(t.init(shle::view(flat), shle::Box{10, 10, 30, 20}));  // no texture
  EXPECT_FALSE(t.update(shle::view(flat), &b));
  const Rendered& r = rendered();
  EXPECT_FALSE(t.init(shle::view(r.gray), shle::Box{5000, 10, 5100, 40}));     // outside
  EXPECT_FALSE(t.init(shle::view(r.gray), shle::Box{10, 10, 11.5, 40}));       // 1 px wide
  EXPECT_FALSE(t.init(shle::view(r.gray), shle::Box{NAN, 10, 100, 40}));
  // Partly outside: clipped to the image, then tracked.
  EXPECT_TRUE(t.init(shle::view(r.gray), shle::Box{-30, 100, 60, 140}));
  ASSERT_TRUE(t.update(shle::view(r.gray), &b));
  EXPECT_EQ(b.x0, 0);
  EXPECT_EQ(b.width(), 60);
}

TEST(NccTracker, MinimumScoreReportsLoss) {
  const Rendered& r = rendered();
  shle::GrayImage noise = r.gray;
  std::uint32_t s = 1;
  for (auto& p : noise.px) {
    s = s * 1664525u + 1013904223u;
    p = static_cast<std::uint8_t>(s >> 24);
  }
  shle::NccOptions o;
  o.min_score = 0.5;
  shle::NccTracker t(o);
  ASSERT_TRUE(t.init(shle::view(r.gray), r.box));
  shle::Box b{1, 2, 3, 4};
  EXPECT_FALSE(t.update(shle::view(noise), &b));
  EXPECT_EQ(b.x0, 1);  // untouched
  EXPECT_LT(t.last_score(), 0.5);
}

TEST(NccTracker, Factory) {
  EXPECT_EQ(shle::make_tracker("ncc", {})->name(), "ncc");
  EXPECT_EQ(shle::make_tracker("mil", {})->name(), "mil");
  EXPECT_EQ(shle::make_tracker("none", {}), nullptr);
  EXPECT_ANY_THROW(shle::make_tracker("kcf", {}));
}

TEST(MilTracker, RecoversKnownShiftsWithinTwoPixels) {
  const Rendered& r = rendered();
  const double x = std::trunc(r.box.x0), y = std::trunc(r.box.y0);
  const int shifts[][2] = {{0, 0}, {6, -3}, {-12, 8}, {18, 0}, {0, -15}};
  for (const auto& s : shifts) {
    shle::MilTracker t;
    ASSERT_TRUE(t.init(shle::view(r.gray), r.box));
    shle::Box b;
    ASSERT_TRUE(t.update(shle::view(shifted(r.gray, s[0], s[1])), &b));
    EXPECT_NEAR(b.x0, x + s[0], 2.0) << s[0] << "," << s[1];
    EXPECT_NEAR(b.y0, y + s[1], 2.0) << s[0] << "," << s[1];
  }
}

TEST(MilTracker, DeterministicAndFollowsTheNextFrame) {
  const Rendered& r = rendered();
  shle::MilTracker a, b;
  ASSERT_TRUE(a.init(shle::view(r.gray), r.box));
  ASSERT_TRUE(b.init(shle::view(r.gray), r.box));
  shle::Box ba, bb;
  ASSERT_TRUE(a.update(shle::view(r.next), &ba));
  ASSERT_TRUE(b.update(shle::view(r.next), &bb));
  EXPECT_EQ(ba.x0, bb.x0);
  EXPECT_EQ(ba.y0, bb.y0);
  shle::CentreDistance c;
  ASSERT_TRUE(shle::centre_distance(ba, r.next_box, &c));
  EXPECT_LT(c.cpd, 8.0);
  shle::GrayImage flat;
  flat.width = 64;
  flat.height = 48;
  flat.px.assign(64 * 48, 7);
  shle::MilTracker m;
  EXPECT_FALSE(m.update(shle::view(flat), &ba));               // not seeded
  EXPECT_FALSE(m.init(shle::view(flat), shle::Box{1, 1, 3, 3}));  // too small
}

}  // namespace
