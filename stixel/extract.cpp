#include "stixel/extract.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "stixel/error.h"

namespace stixel {
namespace {

const char* attribute_name(int attrs, int a) {
  static const char* three[] = {"vB", "vT", "P"};
  static const char* four[] = {"vB", "vT", "d_res", "P"};
  return attrs == 3 ? three[a] : four[a];
}

[[noreturn]] void bad_value(int attrs, int a, int n, int u, float v) {
  throw Error("prediction: " + std::string(attribute_name(attrs, a)) + " of candidate " +
              std::to_string(n) + ", column " + std::to_string(u) + " is " + std::to_string(v) +
              " (non-finite or out of range)");
}

// int(v_hat * H + 1) as Python computes it on a numpy float32 scalar (promoted
// to double, where the product with an integer H < 2^29 is exact).
std::int32_t row_of(float v_hat, int height, int attrs, int a, int n, int u) {
  const double r = static_cast<double>(v_hat) * height + 1.0;
  if (!(r > -2147483648.0 && r < 2147483648.0)) bad_value(attrs, a, n, u, v_hat);
  return static_cast<std::int32_t>(r);  // truncation toward zero, as Python's int()
}

void validate(int attrs, int candidates, int columns, const Anchors& anchors,
              const ExtractOptions& o) {
  if (attrs != 3 && attrs != 4)
    throw Error("prediction: expected 3 (vB, vT, P) or 4 (vB, vT, d_res, P) attributes, got " +
                std::to_string(attrs));
  if (candidates < 1 || columns < 1)
    throw Error("prediction: empty shape [" + std::to_string(attrs) + ", " +
                std::to_string(candidates) + ", " + std::to_string(columns) + "]");
  if (anchors.size() != candidates)
    throw Error("prediction has " + std::to_string(candidates) + " candidates per column but " +
                std::to_string(anchors.size()) + " depth anchors are configured");
  if (!(o.threshold >= 0.0 && o.threshold <= 1.0))
    throw Error("threshold must be in [0, 1], got " + std::to_string(o.threshold));
  if (o.image_height < 1 || o.image_height > (1 << 28))
    throw Error("image height must be in [1, 2^28], got " + std::to_string(o.image_height));
  if (o.stixel_width < 1 || static_cast<long long>(o.stixel_width) * columns > (1 << 28))
    throw Error("stixel width " + std::to_string(o.stixel_width) + " with " +
                std::to_string(columns) + " columns is out of range");
  if (!(o.depth_scale > 0.0) || !std::isfinite(o.depth_scale))
    throw Error("depth scale must be positive and finite, got " + std::to_string(o.depth_scale));
}

}  // namespace

double decode_depth_residual(double anchor, float d_res) {
  // The reference's LOG_DEPTH_EPS guards the anchor (not the result).
  return std::exp(std::log(std::max(anchor, 1e-6)) + static_cast<double>(d_res));
}

void extract_into(StixelWorld& out, const float* prediction, int attrs, int candidates,
                  int columns, const Anchors& anchors, const ExtractOptions& o) {
  validate(attrs, candidates, columns, anchors, o);
  if (!prediction) throw Error("prediction: null data pointer");
  const std::size_t plane = static_cast<std::size_t>(candidates) * columns;
  const float* vb_hat = prediction;
  const float* vt_hat = prediction + plane;
  const float* res = attrs == 4 ? prediction + 2 * plane : nullptr;
  const float* prob = prediction + (attrs - 1) * plane;
  const int p_attr = attrs - 1;
  std::size_t kept = 0;
  for (std::size_t i = 0; i < plane; ++i) kept += static_cast<double>(prob[i]) >= o.threshold;
  out.stixels.reserve(out.stixels.size() + kept);

  for (int u = 0; u < columns; ++u) {
    for (int n = 0; n < candidates; ++n) {
      const std::size_t i = static_cast<std::size_t>(n) * columns + u;
      const float p = prob[i];
      if (!(static_cast<double>(p) >= o.threshold)) continue;  // NaN is never kept
      if (!std::isfinite(p)) bad_value(attrs, p_attr, n, u, p);
      Stixel s;
      s.u = u * o.stixel_width;
      s.vT = row_of(vt_hat[i], o.image_height, attrs, 1, n, u);
      s.vB = row_of(vb_hat[i], o.image_height, attrs, 0, n, u);
      double d = anchors.depth[n];
      if (res) {
        if (!std::isfinite(res[i])) bad_value(attrs, 2, n, u, res[i]);
        d = decode_depth_residual(anchors.exact_at(n), res[i]);
      }
      if (o.depth_scale != 1.0) d *= o.depth_scale;
      s.d = static_cast<float>(d);
      if (!std::isfinite(s.d)) bad_value(attrs, 2, n, u, res ? res[i] : 0.0f);
      s.confidence = p;
      s.width = o.stixel_width;
      out.stixels.push_back(s);
    }
  }
}

StixelWorld extract(const float* prediction, int attrs, int candidates, int columns,
                    const Anchors& anchors, const ExtractOptions& options) {
  StixelWorld world;
  extract_into(world, prediction, attrs, candidates, columns, anchors, options);
  return world;
}

}  // namespace stixel
