#include <algorithm>
#include <cmath>
#include <string>

#include "stixel/alpha_composite.h"
#include "stixel/error.h"
#include "stixel/render.h"

namespace stixel {
namespace {

// The transparent layer Pillow draws on: colour and alpha per pixel, later
// drawings replacing earlier ones.
struct Layer {
  int w, h;
  std::vector<std::uint8_t> rgb, alpha;
  Layer(int w_, int h_) : w(w_), h(h_), rgb(static_cast<std::size_t>(w_) * h_ * 3), alpha(static_cast<std::size_t>(w_) * h_) {}
  void set(std::int64_t x, std::int64_t y, const Rgb& c, std::uint8_t a) {
    if (x < 0 || y < 0 || x >= w || y >= h) return;
    const std::size_t p = static_cast<std::size_t>(y) * w + x;
    rgb[3 * p] = c[0];
    rgb[3 * p + 1] = c[1];
    rgb[3 * p + 2] = c[2];
    alpha[p] = a;
  }
  // Bresenham, each pixel doubled across the line's minor axis: 2 px wide.
  void line(int x0, int y0, int x1, int y1, const Rgb& c, std::uint8_t a) {
    const int dx = std::abs(x1 - x0), dy = -std::abs(y1 - y0);
    const int sx = x0 < x1 ? 1 : -1, sy = y0 < y1 ? 1 : -1;
    const bool steep = -dy > dx;
    int err = dx + dy;
    for (;;) {
      set(x0, y0, c, a);
      set(x0 + (steep ? 1 : 0), y0 + (steep ? 0 : 1), c, a);
      if (x0 == x1 && y0 == y1) break;
      const int e2 = 2 * err;
      if (e2 >= dy) {
        err += dy;
        x0 += sx;
      }
      if (e2 <= dx) {
        err += dx;
        y0 += sy;
      }
    }
  }
};

Rgb cluster_rgb(int id, int max_id) {
  if (id < 0) return {127, 127, 127};
  const int denom = std::max(1, max_id);
  const double t = static_cast<double>(id % (denom + 1)) / denom;
  auto byte = [](double v) { return static_cast<std::uint8_t>(std::clamp(v, 0.0, 1.0) * 255); };
  return {byte(t), byte(1.0 - std::fabs(2.0 * t - 1.0)), byte(1.0 - t)};
}

}  // namespace

RgbImage render_bev_fitted(const StixelWorld& world, const Projection& projection, const BevOptions& o) {
  if (o.width < 2 || o.height < 2 || static_cast<std::int64_t>(o.width) * o.height > (1 << 26))
    throw Error("bev: canvas size " + std::to_string(o.width) + "x" + std::to_string(o.height) + " out of range");
  if (o.lateral_axis < 0 || o.lateral_axis > 2 || o.forward_axis < 0 || o.forward_axis > 2 ||
      o.lateral_axis == o.forward_axis)
    throw Error("bev: lateral and forward axes must be two different values of 0, 1, 2");
  if (!(o.line_alpha >= 0.0 && o.line_alpha <= 1.0)) throw Error("bev: line alpha must be in [0, 1]");
  RgbImage out;
  out.width = o.width;
  out.height = o.height;
  out.pixels.resize(static_cast<std::size_t>(o.width) * o.height * 3);
  for (std::size_t p = 0; p < out.pixels.size(); p += 3)
    for (int k = 0; k < 3; ++k) out.pixels[p + k] = o.background[k];

  struct Item {
    std::size_t index;
    double tl, tf, bl, bf;  // lateral / forward of the top and bottom points
  };
  std::vector<Item> items;
  int max_cluster = -1;
  double lmin = INFINITY, lmax = -INFINITY, fmin = INFINITY, fmax = -INFINITY;
  for (std::size_t i = 0; i < world.stixels.size(); ++i) {
    const Stixel& s = world.stixels[i];
    if (!(static_cast<double>(s.confidence) >= o.min_confidence)) continue;
    const Point3 top = projection.point(s.u, s.vT, s.d), bottom = projection.point(s.u, s.vB, s.d);
    Item it{i, top[o.lateral_axis], top[o.forward_axis], bottom[o.lateral_axis], bottom[o.forward_axis]};
    if (o.flip_lateral) {
      it.tl = -it.tl;
      it.bl = -it.bl;
    }
    for (double l : {it.tl, it.bl})
      if (!std::isnan(l)) lmin = std::min(lmin, l), lmax = std::max(lmax, l);  // nanmin / nanmax
    for (double f : {it.tf, it.bf})
      if (!std::isnan(f)) fmin = std::min(fmin, f), fmax = std::max(fmax, f);
    max_cluster = std::max(max_cluster, s.cluster);
    items.push_back(it);
  }
  if (items.empty() || !std::isfinite(lmin) || !std::isfinite(lmax) || !std::isfinite(fmin) || !std::isfinite(fmax))
    return out;
  if (lmax <= lmin) lmax = lmin + 1e-6;
  if (fmax <= fmin) fmax = fmin + 1e-6;
  if (max_cluster < 0) max_cluster = 1;
  auto to_px = [&](double l, double f, int* px, int* py) {
    const double ln = (l - lmin) / (lmax - lmin), fn = (f - fmin) / (fmax - fmin);
    *px = static_cast<int>(std::clamp(ln * (o.width - 1), 0.0, static_cast<double>(o.width - 1)));
    *py = static_cast<int>(std::clamp((1.0 - fn) * (o.height - 1), 0.0, static_cast<double>(o.height - 1)));
  };

  Layer layer(o.width, o.height);
  const std::uint8_t line_a = static_cast<std::uint8_t>(o.line_alpha * 255);
  for (const Item& it : items) {
    if (!std::isfinite(it.tl) || !std::isfinite(it.tf) || !std::isfinite(it.bl) || !std::isfinite(it.bf)) continue;
    const Stixel& s = world.stixels[it.index];
    Rgb c{0, 0, 0};
    switch (o.color) {
      case BevOptions::Color::Depth: c = depth_color(s.d); break;
      case BevOptions::Color::Cluster: c = cluster_rgb(s.cluster, max_cluster); break;
      case BevOptions::Color::Confidence: {
        const double p = std::clamp(static_cast<double>(s.confidence), 0.0, 1.0);
        c = {static_cast<std::uint8_t>((1.0 - p) * 255.0), static_cast<std::uint8_t>(p * 255.0), 0};
        break;
      }
    }
    int x0, y0, x1, y1;
    to_px(it.tl, it.tf, &x0, &y0);
    to_px(it.bl, it.bf, &x1, &y1);
    layer.line(x0, y0, x1, y1, c, line_a);
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) layer.set(x1 + dx, y1 + dy, c, 255);
  }
  for (std::size_t p = 0; p < layer.alpha.size(); ++p) {
    if (!layer.alpha[p]) continue;
    const PilComposite composite(layer.alpha[p]);
    for (int k = 0; k < 3; ++k) out.pixels[3 * p + k] = composite(layer.rgb[3 * p + k], out.pixels[3 * p + k]);
  }
  return out;
}

}  // namespace stixel
