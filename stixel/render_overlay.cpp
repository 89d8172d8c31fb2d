#include <algorithm>
#include <numeric>
#include <string>

#include "stixel/alpha_composite.h"
#include "stixel/error.h"
#include "stixel/render.h"

namespace stixel {
namespace {

std::int64_t floor_div2(std::int64_t x) { return x >= 0 ? x / 2 : -((-x + 1) / 2); }

}  // namespace

RgbImage render_overlay(const StixelWorld& world, const RgbImage& bg, const OverlayOptions& o) {
  if (bg.width <= 0 || bg.height <= 0 ||
      bg.pixels.size() != static_cast<std::size_t>(bg.width) * bg.height * 3)
    throw Error("overlay: background must be width*height*3 RGB bytes");
  if (!(o.alpha >= 0.0 && o.alpha <= 1.0))
    throw Error("overlay: alpha must be in [0, 1], got " + std::to_string(o.alpha));
  const std::int64_t W = bg.width, H = bg.height;

  std::vector<std::size_t> order(world.stixels.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return world.stixels[a].d > world.stixels[b].d;
  });

  // The transparent layer: colour per pixel, 0 alpha where nothing was drawn.
  std::vector<std::uint8_t> layer(bg.pixels.size(), 0);
  std::vector<std::uint8_t> drawn(static_cast<std::size_t>(W * H), 0);
  for (std::size_t i : order) {
    const Stixel& s = world.stixels[i];
    if (!(static_cast<double>(s.confidence) >= o.min_confidence)) continue;
    const std::int64_t off = floor_div2(s.width);
    const std::int64_t left = std::max<std::int64_t>(0, std::min<std::int64_t>(s.u - off, s.u + off));
    const std::int64_t right = std::min<std::int64_t>(W - 1, std::max<std::int64_t>(s.u - off, s.u + off));
    const std::int64_t top = std::max<std::int64_t>(0, std::min(s.vT, s.vB));
    const std::int64_t bottom = std::min<std::int64_t>(H - 1, std::max(s.vT, s.vB));
    if (right <= left || bottom <= top) continue;
    const Rgb c = o.color_by_cluster ? cluster_color(s.cluster, world.context.clusters)
                                     : depth_color(s.d);
    for (std::int64_t y = top; y <= bottom; ++y)
      for (std::int64_t x = left; x <= right; ++x) {
        const std::size_t p = static_cast<std::size_t>(y * W + x);
        layer[3 * p] = c[0];
        layer[3 * p + 1] = c[1];
        layer[3 * p + 2] = c[2];
        drawn[p] = 1;
      }
  }

  RgbImage out = bg;
  const std::uint32_t a = static_cast<std::uint32_t>(o.alpha * 255);
  if (a == 0) return out;
  const PilComposite composite(a);
  for (std::size_t p = 0; p < drawn.size(); ++p) {
    if (!drawn[p]) continue;
    for (int k = 0; k < 3; ++k)
      out.pixels[3 * p + k] = composite(layer[3 * p + k], bg.pixels[3 * p + k]);
  }
  return out;
}

}  // namespace stixel
