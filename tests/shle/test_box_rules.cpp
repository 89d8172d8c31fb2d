// Box rules on hand-made candidate sets (1280x720 image).
#include <gtest/gtest.h>

#include <cmath>

#include "shle/box_rules.h"
#include "shle/error.h"

namespace {

shle::Candidate cand(double x0, double y0, double x1, double y1, double score) {
  return shle::Candidate{shle::Box{x0, y0, x1, y1}, score};
}

shle::BoxRuleOptions rule(shle::BoxRule r) {
  shle::BoxRuleOptions o;
  o.rule = r;
  return o;
}

TEST(BoxRules, WidestKeepsWidestAboveThreshold) {
  std::vector<shle::Candidate> c = {
      cand(500, 100, 600, 150, 0.90),   // w 100
      cand(400, 100, 700, 150, 0.50),   // w 300  <- widest passing
      cand(0, 100, 800, 150, 0.20),     // w 800 but score too low
      cand(300, 300, 600, 350, 0.31),   // w 300, tie: the first one wins
      cand(0, 0, 1000, 50, 0.30),       // exactly 0.3: not > 0.3
  };
  EXPECT_EQ(shle::select_box(c, 1280, 720, rule(shle::BoxRule::Widest)), 1);
  shle::BoxRuleOptions low = rule(shle::BoxRule::Widest);
  low.min_score = 0.1;
  EXPECT_EQ(shle::select_box(c, 1280, 720, low), 4);  // 0.30 now passes, width 1000
}

TEST(BoxRules, PaperDropsLeftLowTopThenBestScore) {
  std::vector<shle::Candidate> c = {
      cand(100, 200, 600, 260, 0.99),   // entirely in the left half
      cand(500, 400, 900, 500, 0.95),   // entirely in the lower half
      cand(600, 0.5, 900, 100, 0.97),   // touches the top edge
      cand(450, 250, 1100, 290, 0.60),
      cand(450, 240, 1000, 280, 0.70),  // best remaining
      cand(460, 240, 1000, 280, 0.70),  // same score later: not chosen
      cand(700, 100, 800, 150, 0.25),   // below the score gate
  };
  EXPECT_EQ(shle::select_box(c, 1280, 720, rule(shle::BoxRule::Paper)), 4);
  // The released rule picks the widest instead.
  EXPECT_EQ(shle::select_box(c, 1280, 720, rule(shle::BoxRule::Widest)), 3);
}

TEST(BoxRules, PaperGeometricTests) {
  // Spans the centre line: kept by the whole-box test, dropped by the centre test.
  std::vector<shle::Candidate> c = {cand(100, 200, 700, 260, 0.9), cand(900, 500, 1000, 700, 0.5)};
  EXPECT_EQ(shle::select_box(c, 1280, 720, rule(shle::BoxRule::Paper)), 0);
  shle::BoxRuleOptions centre = rule(shle::BoxRule::Paper);
  centre.paper.centre_test = true;
  EXPECT_EQ(shle::select_box(c, 1280, 720, centre), -1);
  // A box ending exactly on the centre line lies in the left half.
  std::vector<shle::Candidate> edge = {cand(100, 200, 640, 260, 0.9), cand(641, 200, 700, 260, 0.4)};
  EXPECT_EQ(shle::select_box(edge, 1280, 720, rule(shle::BoxRule::Paper)), 1);
  // Starting exactly on the horizontal centre line counts as low; y0 < 1 touches the top.
  std::vector<shle::Candidate> low = {cand(700, 360, 900, 400, 0.9), cand(700, 0.99, 900, 40, 0.8),
                                      cand(700, 1.0, 900, 40, 0.7)};
  EXPECT_EQ(shle::select_box(low, 1280, 720, rule(shle::BoxRule::Paper)), 2);
  shle::BoxRuleOptions strict = rule(shle::BoxRule::Paper);
  strict.paper.top_touch_px = 5;
  EXPECT_EQ(shle::select_box(low, 1280, 720, strict), -1);
}

TEST(BoxRules, LoneCandidateAndEmptySets) {
  std::vector<shle::Candidate> lone = {cand(10, 600, 100, 700, 0.8), cand(0, 0, 10, 10, 0.1)};
  // One candidate passes the score gate: taken as it is.
  EXPECT_EQ(shle::select_box(lone, 1280, 720, rule(shle::BoxRule::Paper)), 0);
  shle::BoxRuleOptions filtered = rule(shle::BoxRule::Paper);
  filtered.paper.filter_single = true;
  EXPECT_EQ(shle::select_box(lone, 1280, 720, filtered), -1);
  EXPECT_EQ(shle::select_box({}, 1280, 720, rule(shle::BoxRule::Paper)), -1);
  EXPECT_EQ(shle::select_box({cand(0, 0, 9, 9, 0.3)}, 1280, 720, rule(shle::BoxRule::Widest)), -1);
  // Non-finite boxes are never chosen.
  std::vector<shle::Candidate> nan = {cand(NAN, 0, 1000, 100, 0.9), cand(700, 100, 800, 200, 0.5)};
  EXPECT_EQ(shle::select_box(nan, 1280, 720, rule(shle::BoxRule::Widest)), 1);
}

TEST(BoxRules, Names) {
  EXPECT_EQ(shle::parse_box_rule("paper"), shle::BoxRule::Paper);
  EXPECT_EQ(shle::parse_box_rule("widest"), shle::BoxRule::Widest);
  EXPECT_THROW(shle::parse_box_rule("best"), shle::Error);
  EXPECT_STREQ(shle::box_rule_name(shle::BoxRule::Widest), "widest");
}

}  // namespace
