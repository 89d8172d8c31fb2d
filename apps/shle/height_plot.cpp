#include "apps/shle/height_plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace shleapp {
namespace {

const Colour kWhite{255, 255, 255}, kAxis{40, 40, 40}, kGrid{225, 225, 225};
const Colour kRaw{40, 110, 220}, kFiltered{215, 40, 40}, kTruth{20, 150, 60}, kText{20, 20, 20};

std::string fmt(const char* f, double v) {
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

}  // namespace

double nice_step(double span, int target) {
  if (!(span > 0) || !std::isfinite(span)) return 1.0;
  double raw = span / std::max(1, target);
  double p = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 2.5, 5.0, 10.0})
    if (m * p >= raw) return m * p;
  return 10 * p;
}

Canvas draw_height_plot(const HeightPlotData& d, int W, int H) {
  Canvas c(W, H, kWhite);
  const int left = 90, right = W - 20, top = 60, bottom = H - 60;
  double lo = INFINITY, hi = -INFINITY;
  for (const auto& p : d.raw) lo = std::min(lo, p.second), hi = std::max(hi, p.second);
  for (const auto& p : d.filtered) lo = std::min(lo, p.second), hi = std::max(hi, p.second);
  if (d.has_gt) lo = std::min(lo, d.gt), hi = std::max(hi, d.gt);
  if (!std::isfinite(lo)) lo = 0, hi = 1;
  if (hi - lo < 0.1) {
    double mid = 0.5 * (lo + hi);
    lo = mid - 0.05;
    hi = mid + 0.05;
  }
  double pad = 0.08 * (hi - lo);
  lo -= pad;
  hi += pad;
  const int nx = std::max(1, d.frames - 1);
  auto X = [&](double f) { return left + (right - left) * f / nx; };
  auto Y = [&](double h) { return bottom - (bottom - top) * (h - lo) / (hi - lo); };

  double ys = nice_step(hi - lo, 6);
  for (double t = std::ceil(lo / ys) * ys; t <= hi; t += ys) {
    c.line(left, Y(t), right, Y(t), kGrid);
    std::string s = fmt(ys < 0.1 ? "%.2f" : "%.1f", t);
    c.text(left - 8 - Canvas::text_width(s), static_cast<int>(Y(t)) - 7, s, kText);
  }
  double xs = std::max(1.0, nice_step(nx, 8));
  for (double f = 0; f <= nx; f += xs) {
    c.line(X(f), bottom, X(f), bottom + 5, kAxis);
    std::string s = fmt("%.0f", f);
    c.text(static_cast<int>(X(f)) - Canvas::text_width(s) / 2, bottom + 10, s, kText);
  }
  c.line(left, top, left, bottom, kAxis, 2);
  c.line(left, bottom, right, bottom, kAxis, 2);
  c.text((left + right) / 2 - Canvas::text_width("frame") / 2, H - 24, "frame", kText);
  c.text(8, top - 22, "height (m)", kText);

  if (d.has_gt) c.line(left, Y(d.gt), right, Y(d.gt), kTruth, 2, 8);
  for (std::size_t i = 1; i < d.filtered.size(); ++i)
    c.line(X(d.filtered[i - 1].first), Y(d.filtered[i - 1].second), X(d.filtered[i].first),
           Y(d.filtered[i].second), kFiltered, 2);
  for (const auto& p : d.filtered) c.square_marker(X(p.first), Y(p.second), 1, kFiltered);
  for (const auto& p : d.raw) c.square_marker(X(p.first), Y(p.second), 2, kRaw);

  // Legend and headline.
  int lx = right - 250, ly = 12;
  c.fill_rect(lx, ly + 4, lx + 8, ly + 12, kRaw);
  c.text(lx + 16, ly + 2, "raw", kText);
  c.line(lx + 70, ly + 8, lx + 90, ly + 8, kFiltered, 2);
  c.text(lx + 96, ly + 2, "filtered", kText);
  if (d.has_gt) {
    c.line(lx, ly + 28, lx + 20, ly + 28, kTruth, 2, 4);
    c.text(lx + 26, ly + 22, "truth " + fmt("%.2f", d.gt), kText);
  }
  std::string head = d.has_scene ? "scene height " + fmt("%.3f", d.scene) + " m" : "no height";
  c.text(left, 6, head, kText);
  return c;
}

}  // namespace shleapp
