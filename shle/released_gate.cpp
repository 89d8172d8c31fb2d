#include "shle/released_gate.h"

#include <algorithm>
#include <cmath>

namespace shle {

double released_iou(const Box& a, const Box& b) {
  // Truncated coordinates stay exact integers in double (boxes are image-sized).
  const double ax0 = std::trunc(a.x0), ay0 = std::trunc(a.y0), ax1 = std::trunc(a.x1), ay1 = std::trunc(a.y1);
  const double bx0 = std::trunc(b.x0), by0 = std::trunc(b.y0), bx1 = std::trunc(b.x1), by1 = std::trunc(b.y1);
  const double xa = std::max(ax0, bx0), ya = std::max(ay0, by0);
  const double xb = std::min(ax1, bx1), yb = std::min(ay1, by1);
  const double inter = std::max(0.0, xb - xa + 1) * std::max(0.0, yb - ya + 1);
  const double area_a = (ax1 - ax0 + 1) * (ay1 - ay0 + 1), area_b = (bx1 - bx0 + 1) * (by1 - by0 + 1);
  const double den = area_a + area_b - inter;
  return den == 0 ? 0.0 : inter / den;
}

bool released_gate(const Box& p, const Box& gt) {
  const double row_dis = std::fabs(p.x1 - gt.x0), col_dis = std::fabs(p.y0 - gt.y0);
  return released_iou(p, gt) > 0.0 || (row_dis < 200 && col_dis < 20);
}

}  // namespace shle
