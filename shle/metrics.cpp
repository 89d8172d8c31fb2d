#include "shle/metrics.h"

#include <cmath>

#include "shle/error.h"

namespace shle {

HeightError height_error(double estimate, double truth) {
  if (!(truth > 0) || !std::isfinite(truth) || !std::isfinite(estimate))
    throw Error("height error needs a finite estimate and a positive finite true height");
  HeightError e;
  e.he = estimate - truth;
  e.her = e.he / truth;
  e.he_abs = std::fabs(e.he);
  e.her_abs = std::fabs(e.her);
  return e;
}

HeightErrorSummary summarize_height_errors(const std::vector<double>& est, double truth) {
  HeightErrorSummary s;
  for (double v : est) {
    HeightError e = height_error(v, truth);
    s.mean.he += e.he;
    s.mean.her += e.her;
    s.mean.he_abs += e.he_abs;
    s.mean.her_abs += e.her_abs;
  }
  s.n = est.size();
  if (s.n) {
    double k = 1.0 / static_cast<double>(s.n);
    s.mean.he *= k;
    s.mean.her *= k;
    s.mean.he_abs *= k;
    s.mean.her_abs *= k;
  }
  return s;
}

bool centre_distance(const Box& p, const Box& t, CentreDistance* out) {
  if (!p.finite() || !t.finite()) return false;
  const double w = t.width(), h = t.height();
  if (!(w > 0) || !(h > 0)) return false;
  const double dx = 0.5 * (p.x0 + p.x1) - 0.5 * (t.x0 + t.x1);
  const double dy = 0.5 * (p.y0 + p.y1) - 0.5 * (t.y0 + t.y1);
  out->cpd = std::sqrt(dx * dx + dy * dy);
  out->rcpda = out->cpd / (w * h);
  out->rcpdh = out->cpd / std::sqrt(w * w + h * h);
  return true;
}

}  // namespace shle
