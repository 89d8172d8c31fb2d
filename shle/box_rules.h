// Choosing one box per frame among a box source's candidates.
//
// paper  ("Faster RCNN + Filter Rule", applied in order): drop boxes in the
//        left-most 50 % of the image, drop boxes in the lowest 50 %, drop boxes
//        touching the top edge, keep the highest score (first on ties).
//        The paper does not pin the geometric tests down; the choices here:
//        a box is "in the left-most part" when it lies entirely left of
//        left_fraction * width (x1 <= that line), "in the lowest part" when it lies
//        entirely below (1 - bottom_fraction) * height (y0 >= that line), and
//        "touching the top edge" when y0 < top_touch_px. centre_test = true tests
//        the box centre instead of the whole box for the first two rules.
// widest (the released code): keep the box with the largest width x1 - x0 (first
//        on ties); the score only gates.
// Both first keep candidates with score > min_score (the released 0.3). The
// rules choose among several boxes: when exactly one candidate passes the score
// gate it is taken as it is, unless paper.filter_single asks to apply the
// paper's position filters to a lone box as well.
#pragma once

#include <string>
#include <vector>

#include "shle/types.h"

namespace shle {

enum class BoxRule { Paper, Widest };

struct PaperRuleOptions {
  bool centre_test = false;
  double left_fraction = 0.5;
  double bottom_fraction = 0.5;
  double top_touch_px = 1.0;
  bool filter_single = false;
};

struct BoxRuleOptions {
  BoxRule rule = BoxRule::Paper;
  double min_score = 0.3;
  PaperRuleOptions paper;
};

// "paper" / "widest"; throws shle::Error for anything else.
BoxRule parse_box_rule(const std::string& name);
const char* box_rule_name(BoxRule rule);

// Index of the chosen candidate, or -1 when none survives the rule.
int select_box(const std::vector<Candidate>& candidates, int image_width, int image_height,
               const BoxRuleOptions& options);

}  // namespace shle
