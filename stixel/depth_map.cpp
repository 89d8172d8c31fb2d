#include "stixel/depth_map.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "stixel/error.h"
#include "stixel/image_header.h"

namespace stixel {
namespace {

constexpr std::int64_t kMaxPixels = std::int64_t(1) << 28;

// Python's floor division (the reference computes width // 2 on Python ints).
std::int64_t floor_div2(std::int64_t x) { return x >= 0 ? x / 2 : -((-x + 1) / 2); }

}  // namespace

DepthMap depth_map(const StixelWorld& world, int width, int height) {
  std::int64_t w = width, h = height;
  if (w <= 0 || h <= 0) {
    w = world.context.calibration.width;
    h = world.context.calibration.height;
  }
  if (w <= 0 || h <= 0) {
    int iw = 0, ih = 0;
    if (image_size(world.image.data(), world.image.size(), &iw, &ih)) {
      w = iw;
      h = ih;
    }
  }
  if (w <= 0 || h <= 0) {
    if (world.stixels.empty())
      throw Error("depth map: no size (no calibration size, image or stixels)");
    w = INT64_MIN;
    h = INT64_MIN;
    for (const Stixel& s : world.stixels) {
      w = std::max<std::int64_t>(w, s.u + std::max<std::int64_t>(1, floor_div2(s.width)));
      h = std::max<std::int64_t>(h, s.vB);
    }
    ++w;
    ++h;
  }
  if (w <= 0 || h <= 0 || w * h > kMaxPixels)
    throw Error("depth map: invalid size " + std::to_string(w) + "x" + std::to_string(h));

  DepthMap m;
  m.width = static_cast<int>(w);
  m.height = static_cast<int>(h);
  m.depth.assign(static_cast<std::size_t>(w * h), INFINITY);
  for (const Stixel& s : world.stixels) {
    const std::int64_t off = floor_div2(s.width);
    const std::int64_t left = std::max<std::int64_t>(0, s.u - off);
    const std::int64_t right = std::min<std::int64_t>(w - 1, s.u + off);
    const std::int64_t top = std::max<std::int64_t>(0, std::min(s.vT, s.vB));
    const std::int64_t bottom = std::min<std::int64_t>(h - 1, std::max(s.vT, s.vB));
    if (right <= left || bottom <= top) continue;
    for (std::int64_t y = top; y <= bottom; ++y) {
      float* row = m.depth.data() + y * w;
      for (std::int64_t x = left; x <= right; ++x)
        // numpy.minimum: NaN wins.
        row[x] = (std::isnan(row[x]) || std::isnan(s.d)) ? NAN : std::min(row[x], s.d);
    }
  }
  for (float& v : m.depth)
    if (std::isinf(v)) v = NAN;
  return m;
}

DepthRaster prediction_depth_raster(const float* prediction, int attrs, int candidates,
                                    int columns, const Anchors& anchors, int image_height,
                                    int v_scale, double p_threshold) {
  if (!prediction) throw Error("prediction: null data pointer");
  if (attrs != 3 && attrs != 4)
    throw Error("prediction: expected 3 or 4 attributes, got " + std::to_string(attrs));
  if (candidates < 1 || columns < 1) throw Error("prediction: empty shape");
  if (anchors.size() != candidates)
    throw Error("prediction has " + std::to_string(candidates) + " candidates but " +
                std::to_string(anchors.size()) + " depth anchors");
  if (image_height < 1 || image_height > (1 << 28) || v_scale < 1)
    throw Error("depth raster: invalid image height " + std::to_string(image_height) +
                " or row scale " + std::to_string(v_scale));
  const int H = image_height;
  const int rows = std::max(H / v_scale, 1);
  if (static_cast<std::int64_t>(rows) * columns > kMaxPixels)
    throw Error("depth raster: too large");
  const std::size_t plane = static_cast<std::size_t>(candidates) * columns;
  const float* vb_hat = prediction;
  const float* vt_hat = prediction + plane;
  const float* prob = prediction + (attrs - 1) * plane;

  DepthRaster r;
  r.rows = rows;
  r.columns = columns;
  r.depth.assign(static_cast<std::size_t>(rows) * columns, 0.0f);
  r.valid.assign(r.depth.size(), 0);
  for (int u = 0; u < columns; ++u) {
    int k = 0;
    for (int n = 1; n < candidates; ++n)
      if (prob[static_cast<std::size_t>(n) * columns + u] > prob[static_cast<std::size_t>(k) * columns + u])
        k = n;
    const std::size_t i = static_cast<std::size_t>(k) * columns + u;
    if (p_threshold >= 0 && static_cast<double>(prob[i]) < p_threshold) continue;
    // torch: float32 product, then round half to even.
    const float ft = std::nearbyint(vt_hat[i] * static_cast<float>(H));
    const float fb = std::nearbyint(vb_hat[i] * static_cast<float>(H));
    if (!std::isfinite(ft) || !std::isfinite(fb)) continue;
    std::int64_t vt = static_cast<std::int64_t>(std::clamp<float>(ft, -1.0f, static_cast<float>(H)));
    std::int64_t vb = static_cast<std::int64_t>(std::clamp<float>(fb, -1.0f, static_cast<float>(H)));
    vt = std::clamp<std::int64_t>(vt, 0, H - 1);
    vb = std::clamp<std::int64_t>(vb, 0, H - 1);
    if (vt > vb) std::swap(vt, vb);
    vt = std::clamp<std::int64_t>(vt / v_scale, 0, rows - 1);
    vb = std::clamp<std::int64_t>(vb / v_scale, 0, rows - 1);
    double d = anchors.depth[k];
    if (attrs == 4) d *= std::exp(static_cast<double>(prediction[2 * plane + i]));
    const float depth = static_cast<float>(d);
    if (!std::isfinite(depth) || depth <= 0.0f) continue;
    for (std::int64_t y = vt; y <= vb; ++y) {
      r.depth[static_cast<std::size_t>(y) * columns + u] = depth;
      r.valid[static_cast<std::size_t>(y) * columns + u] = 1;
    }
  }
  return r;
}

}  // namespace stixel
