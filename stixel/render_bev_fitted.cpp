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
class Layer {
 public:
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
  void hline(int x0, int x1, int y, const Rgb& c, std::uint8_t a) {
    for (int x = x0; x <= x1; ++x) set(x, y, c, a);
  }
  // Pillow's ImageDraw.line(width=2) (ImagingDrawWideLine): a quad spanned by
  // the segment and its copy offset by the rounded unit normal, filled by
  // Pillow's scanline polygon code with its float32 crossings and rounding.
  // Checked against Pillow (9.4) on random segments while writing it and by
  // RenderRef.FittedBevMatchesPillow on whole pictures.
  void wide_line(int x0, int y0, int x1, int y1, const Rgb& c, std::uint8_t a) {
    const int dx = x1 - x0, dy = y1 - y0;
    if (dx == 0 && dy == 0) {
      set(x0, y0, c, a);
      return;
    }
    const double hyp = std::hypot(static_cast<double>(dx), static_cast<double>(dy));
    // width 2: ROUND_UP(0.5) = 1, ROUND_DOWN(0.5) = 0, so only the "max" offsets remain.
    const int dxmax = round_down(dy / hyp), dymax = round_down(dx / hyp);
    const int v[4][2] = {{x0, y0 + dymax}, {x1, y1 + dymax}, {x1 + dxmax, y1}, {x0 + dxmax, y0}};
    Edge e[4];
    for (int i = 0; i < 4; ++i) e[i] = Edge(v[i][0], v[i][1], v[(i + 1) % 4][0], v[(i + 1) % 4][1]);
    fill(e, 4, c, a);
  }

 private:
  struct Edge {
    int xmin = 0, xmax = 0, ymin = 0, ymax = 0, x0 = 0, y0 = 0;
    float dx = 0;
    Edge() = default;
    Edge(int ax, int ay, int bx, int by)
        : xmin(std::min(ax, bx)), xmax(std::max(ax, bx)), ymin(std::min(ay, by)), ymax(std::max(ay, by)), x0(ax),
          y0(ay), dx(ay == by ? 0.0f : static_cast<float>(bx - ax) / static_cast<float>(by - ay)) {}
  };
  // Pillow's ROUND_UP / ROUND_DOWN (halves away from / towards zero).
  static int round_up(double f) { return f >= 0 ? static_cast<int>(std::floor(f + 0.5)) : -static_cast<int>(std::floor(std::fabs(f) + 0.5)); }
  static int round_down(double f) { return f >= 0 ? static_cast<int>(std::ceil(f - 0.5)) : -static_cast<int>(std::ceil(std::fabs(f) - 0.5)); }

  // Pillow's polygon_generic: horizontal edges drawn as they are, then per row
  // the sorted crossings (float32) paired, ROUND_UP(start) .. ROUND_DOWN(end).
  void fill(const Edge* e, int n, const Rgb& c, std::uint8_t a) {
    int ymin = h - 1, ymax = 0;
    const Edge* table[4];
    int count = 0;
    for (int i = 0; i < n; ++i) {
      if (e[i].ymin == e[i].ymax) {
        hline(e[i].xmin, e[i].xmax, e[i].ymin, c, a);
        continue;
      }
      ymin = std::min(ymin, e[i].ymin);
      ymax = std::max(ymax, e[i].ymax);
      table[count++] = &e[i];
    }
    ymin = std::max(ymin, 0);
    ymax = std::min(ymax, h - 1);
    float xx[8];
    for (int y = ymin; y <= ymax; ++y) {
      int j = 0;
      for (int i = 0; i < count; ++i) {
        const Edge& cur = *table[i];
        if (y >= cur.ymin && y <= cur.ymax) xx[j++] = static_cast<float>(y - cur.y0) * cur.dx + static_cast<float>(cur.x0);
        if (y == cur.ymax && y < ymax && j > 0) {
          xx[j] = xx[j - 1];
          ++j;
        }
      }
      // At most 8 crossings (4 edges, each counted twice at a vertex): an insertion sort.
      // (std::sort here drew GCC 12's false -Warray-bounds from its 16-element path.)
      for (int p = 1; p < j; ++p) {
        const float v = xx[p];
        int q = p;
        for (; q > 0 && xx[q - 1] > v; --q) xx[q] = xx[q - 1];
        xx[q] = v;
      }
      for (int i = 1; i < j; i += 2) hline(round_up(xx[i - 1]), round_down(xx[i]), y, c, a);
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
    layer.wide_line(x0, y0, x1, y1, c, line_a);
    // Pillow's ellipse in the 3x3 box around the bottom point: a plus.
    for (const auto& d : {std::pair<int, int>{0, -1}, {-1, 0}, {0, 0}, {1, 0}, {0, 1}})
      layer.set(x1 + d.first, y1 + d.second, c, 255);
  }
  for (std::size_t p = 0; p < layer.alpha.size(); ++p) {
    if (!layer.alpha[p]) continue;
    const PilComposite composite(layer.alpha[p]);
    for (int k = 0; k < 3; ++k) out.pixels[3 * p + k] = composite(layer.rgb[3 * p + k], out.pixels[3 * p + k]);
  }
  return out;
}

}  // namespace stixel
