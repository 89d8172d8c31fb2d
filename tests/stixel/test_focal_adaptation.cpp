// Issue 14 item 7: the --train-focal adaptation (camera_depth_scale + extraction's
// depth_scale). A network trained on focal length F sees an object at depth D
// through a camera of focal f as if it were at D * F / f, and an ideal network
// fires the anchor nearest that depth. Two cameras of different focal length
// looking at the same scene must then give depths that agree within the anchors'
// quantisation at what each camera's network saw; without the adaptation they
// differ by the focal ratio.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "stixel/anchors.h"
#include "stixel/extract.h"
#include "stixel/projection.h"

namespace {

struct Seen {
  float d;            // the extracted depth
  double half_step;   // half the anchor spacing around the fired anchor, in scene metres
};

// One column, one firing candidate: the anchor nearest D * F / f.
Seen look(double D, double f, double F, bool adapt) {
  const stixel::Anchors anchors = stixel::tangent_anchors();
  const double seen = D * F / f;
  int best = 0;
  for (int n = 1; n < anchors.size(); ++n)
    if (std::fabs(anchors.depth[n] - seen) < std::fabs(anchors.depth[best] - seen)) best = n;
  std::vector<float> pred(3 * 64, 0.0f);
  for (int n = 0; n < 64; ++n) {
    pred[0 * 64 + n] = 0.6f;  // vB
    pred[1 * 64 + n] = 0.4f;  // vT
  }
  pred[2 * 64 + best] = 0.9f;  // P
  const std::vector<float> K = {static_cast<float>(f), 0, 960, 0, static_cast<float>(f), 640, 0, 0, 1};
  stixel::ExtractOptions o;
  o.threshold = 0.5;
  o.depth_scale = adapt ? stixel::camera_depth_scale(K, F) : 1.0;
  const auto w = stixel::extract(pred.data(), 3, 64, 1, anchors, o);
  EXPECT_EQ(w.stixels.size(), 1u);
  const double lo = best > 0 ? anchors.depth[best] - anchors.depth[best - 1] : 0;
  const double hi = best < 63 ? anchors.depth[best + 1] - anchors.depth[best] : 0;
  return {w.stixels.empty() ? NAN : w.stixels[0].d, std::max(lo, hi) / 2 * f / F};
}

TEST(FocalAdaptation, TwoCamerasAgreeWithinTheAnchorQuantisation) {
  const double F = 2056.28;              // the Waymo FRONT camera the network was trained on
  const double f_a = 1000, f_b = 2600;   // a wide and a long lens
  int compared = 0, far_apart_unadapted = 0;
  for (double D = 6.0; D <= 30.0; D += 0.25) {
    const Seen a = look(D, f_a, F, true), b = look(D, f_b, F, true);
    ASSERT_TRUE(std::isfinite(a.d) && std::isfinite(b.d));
    // Each within its own quantisation of the true depth, hence of each other.
    EXPECT_LE(std::fabs(a.d - D), a.half_step * (1 + 1e-6)) << "D " << D;
    EXPECT_LE(std::fabs(b.d - D), b.half_step * (1 + 1e-6)) << "D " << D;
    EXPECT_LE(std::fabs(a.d - b.d), (a.half_step + b.half_step) * (1 + 1e-6)) << "D " << D;
    // Without the adaptation each camera reports what its network saw.
    const Seen ua = look(D, f_a, F, false), ub = look(D, f_b, F, false);
    far_apart_unadapted += std::fabs(ua.d - ub.d) > a.half_step + b.half_step;
    ++compared;
  }
  EXPECT_GT(compared, 90);
  EXPECT_EQ(far_apart_unadapted, compared) << "the unadapted depths should disagree everywhere";
}

}  // namespace
