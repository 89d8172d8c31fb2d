#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>

#include "stixel/error.h"
#include "stixel/render.h"

namespace stixel {
namespace {

class Canvas {
 public:
  explicit Canvas(const BevOptions& o) : o_(o) {
    img_.width = o.width;
    img_.height = o.height;
    img_.pixels.resize(static_cast<std::size_t>(o.width) * o.height * 3);
    for (std::size_t p = 0; p < img_.pixels.size(); p += 3)
      for (int k = 0; k < 3; ++k) img_.pixels[p + k] = o.background[k];
    scale_x_ = o.width / (2.0 * o.lateral_range);
    scale_y_ = o.height / (o.forward_max - o.forward_min);
  }

  // Canvas coordinates (pixel units, not rounded) of a lateral/forward position.
  void to_canvas(double lateral, double forward, double* x, double* y) const {
    if (o_.flip_lateral) lateral = -lateral;
    *x = (lateral + o_.lateral_range) * scale_x_;
    *y = (o_.forward_max - forward) * scale_y_;
  }

  void set(std::int64_t x, std::int64_t y, const Rgb& c) {
    if (x < 0 || y < 0 || x >= img_.width || y >= img_.height) return;
    std::uint8_t* p = &img_.pixels[(static_cast<std::size_t>(y) * img_.width + x) * 3];
    p[0] = c[0];
    p[1] = c[1];
    p[2] = c[2];
  }

  // Bresenham between the pixels containing the two points; far-off segments
  // are clamped first so a point at 1e9 m cannot make the loop run forever.
  void line(double x0, double y0, double x1, double y1, const Rgb& c) {
    const double lim = 4.0 * std::max(img_.width, img_.height);
    if ((x0 < -lim && x1 < -lim) || (x0 > lim && x1 > lim) || (y0 < -lim && y1 < -lim) ||
        (y0 > lim && y1 > lim))
      return;
    auto clampd = [&](double v) { return std::clamp(v, -lim, lim); };
    std::int64_t ax = static_cast<std::int64_t>(std::floor(clampd(x0)));
    std::int64_t ay = static_cast<std::int64_t>(std::floor(clampd(y0)));
    const std::int64_t bx = static_cast<std::int64_t>(std::floor(clampd(x1)));
    const std::int64_t by = static_cast<std::int64_t>(std::floor(clampd(y1)));
    const std::int64_t dx = std::abs(bx - ax), dy = -std::abs(by - ay);
    const std::int64_t sx = ax < bx ? 1 : -1, sy = ay < by ? 1 : -1;
    std::int64_t err = dx + dy;
    for (;;) {
      set(ax, ay, c);
      if (ax == bx && ay == by) break;
      const std::int64_t e2 = 2 * err;
      if (e2 >= dy) {
        err += dy;
        ax += sx;
      }
      if (e2 <= dx) {
        err += dx;
        ay += sy;
      }
    }
  }

  void dot(double x, double y, const Rgb& c) {
    if (!(std::fabs(x) < 1e9 && std::fabs(y) < 1e9)) return;
    const std::int64_t cx = static_cast<std::int64_t>(std::floor(x));
    const std::int64_t cy = static_cast<std::int64_t>(std::floor(y));
    for (std::int64_t dy = -1; dy <= 1; ++dy)
      for (std::int64_t dx = -1; dx <= 1; ++dx) set(cx + dx, cy + dy, c);
  }

  void grid() {
    const Rgb ring{60, 60, 60}, axis{90, 90, 90};
    double x0, y0, x1, y1;
    // Forward axis through lateral 0, lateral axis at forward 0.
    to_canvas(0.0, o_.forward_min, &x0, &y0);
    to_canvas(0.0, o_.forward_max, &x1, &y1);
    line(x0, y0, x1, y1, axis);
    to_canvas(-o_.lateral_range, 0.0, &x0, &y0);
    to_canvas(o_.lateral_range, 0.0, &x1, &y1);
    line(x0, y0, x1, y1, axis);
    const double far = std::hypot(std::max(std::fabs(o_.forward_min), std::fabs(o_.forward_max)),
                                  o_.lateral_range);
    for (double r = o_.ring_step; r <= far; r += o_.ring_step) {
      // Steps short enough that neighbouring samples are at most ~1 px apart.
      const int n = std::max(16, static_cast<int>(2 * M_PI * r * std::max(scale_x_, scale_y_)));
      double px = 0, py = 0;
      for (int i = 0; i <= n; ++i) {
        const double t = 2 * M_PI * i / n;
        double x, y;
        to_canvas(r * std::sin(t), r * std::cos(t), &x, &y);
        if (i) line(px, py, x, y, ring);
        px = x;
        py = y;
      }
    }
  }

  RgbImage take() { return std::move(img_); }

 private:
  const BevOptions& o_;
  RgbImage img_;
  double scale_x_ = 1, scale_y_ = 1;
};

}  // namespace

RgbImage render_bev(const StixelWorld& world, const Projection& projection, const BevOptions& o) {
  if (o.width < 1 || o.height < 1 || static_cast<std::int64_t>(o.width) * o.height > (1 << 26))
    throw Error("bev: canvas size " + std::to_string(o.width) + "x" + std::to_string(o.height) +
                " out of range");
  if (!(o.lateral_range > 0) || !(o.forward_max > o.forward_min) || !std::isfinite(o.lateral_range) ||
      !std::isfinite(o.forward_min) || !std::isfinite(o.forward_max))
    throw Error("bev: invalid visible area");
  if (o.lateral_axis < 0 || o.lateral_axis > 2 || o.forward_axis < 0 || o.forward_axis > 2 ||
      o.lateral_axis == o.forward_axis)
    throw Error("bev: lateral and forward axes must be two different values of 0, 1, 2");
  if (o.grid && !(o.ring_step > 0)) throw Error("bev: ring step must be positive");

  Canvas canvas(o);
  if (o.grid) canvas.grid();

  std::vector<std::size_t> order(world.stixels.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return world.stixels[a].d > world.stixels[b].d;
  });
  const Rgb noise{110, 110, 110};
  for (std::size_t i : order) {
    const Stixel& s = world.stixels[i];
    if (!(static_cast<double>(s.confidence) >= o.min_confidence)) continue;
    Rgb c{0, 0, 0};
    switch (o.color) {
      case BevOptions::Color::Depth: c = depth_color(s.d); break;
      case BevOptions::Color::Cluster:
        c = s.cluster < 0 ? noise : cluster_color(s.cluster, world.context.clusters);
        break;
      case BevOptions::Color::Confidence: {
        const double p = std::clamp(static_cast<double>(s.confidence), 0.0, 1.0);
        c = {static_cast<std::uint8_t>(255 * (1 - p)), static_cast<std::uint8_t>(255 * p), 0};
        break;
      }
    }
    const Point3 top = projection.point(s.u, s.vT, s.d);
    const Point3 bottom = projection.point(s.u, s.vB, s.d);
    double x0, y0, x1, y1;
    canvas.to_canvas(top[o.lateral_axis], top[o.forward_axis], &x0, &y0);
    canvas.to_canvas(bottom[o.lateral_axis], bottom[o.forward_axis], &x1, &y1);
    if (!std::isfinite(x0) || !std::isfinite(y0) || !std::isfinite(x1) || !std::isfinite(y1)) continue;
    canvas.line(x0, y0, x1, y1, c);
    canvas.dot(x1, y1, c);
  }
  return canvas.take();
}

}  // namespace stixel
