#include "shle/box_rules.h"

#include "shle/error.h"

namespace shle {

BoxRule parse_box_rule(const std::string& name) {
  if (name == "paper") return BoxRule::Paper;
  if (name == "widest") return BoxRule::Widest;
  throw Error("unknown box rule '" + name + "' (use paper or widest)");
}

const char* box_rule_name(BoxRule rule) { return rule == BoxRule::Paper ? "paper" : "widest"; }

int select_box(const std::vector<Candidate>& cands, int image_width, int image_height,
               const BoxRuleOptions& o) {
  int best = -1, passing = 0, lone = -1;
  for (std::size_t i = 0; i < cands.size(); ++i)
    if (cands[i].score > o.min_score && cands[i].box.finite()) {
      ++passing;
      lone = static_cast<int>(i);
    }
  if (passing == 1 && !(o.rule == BoxRule::Paper && o.paper.filter_single)) return lone;
  const double left_line = o.paper.left_fraction * image_width;
  const double low_line = (1.0 - o.paper.bottom_fraction) * image_height;
  for (std::size_t i = 0; i < cands.size(); ++i) {
    const Candidate& c = cands[i];
    const Box& b = c.box;
    if (!(c.score > o.min_score) || !b.finite()) continue;
    if (o.rule == BoxRule::Widest) {
      if (best < 0 || b.width() > cands[best].box.width()) best = static_cast<int>(i);
      continue;
    }
    const PaperRuleOptions& p = o.paper;
    bool in_left = p.centre_test ? 0.5 * (b.x0 + b.x1) < left_line : b.x1 <= left_line;
    bool in_low = p.centre_test ? 0.5 * (b.y0 + b.y1) > low_line : b.y0 >= low_line;
    bool touches_top = b.y0 < p.top_touch_px;
    if (in_left || in_low || touches_top) continue;
    if (best < 0 || c.score > cands[best].score) best = static_cast<int>(i);
  }
  return best;
}

}  // namespace shle
