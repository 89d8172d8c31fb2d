#include "shle/types.h"

#include <cmath>

namespace shle {

bool Box::finite() const {
  return std::isfinite(x0) && std::isfinite(y0) && std::isfinite(x1) && std::isfinite(y1);
}

void to_gray(const RgbImage& in, GrayImage* out) {
  GrayImage& g = *out;
  g.width = in.width;
  g.height = in.height;
  std::size_t n = static_cast<std::size_t>(in.width) * in.height;
  g.px.resize(n);
  const std::uint8_t* p = in.rgb.data();
  for (std::size_t i = 0; i < n; ++i, p += 3)
    g.px[i] = static_cast<std::uint8_t>((77u * p[0] + 150u * p[1] + 29u * p[2] + 128u) >> 8);
}

GrayImage to_gray(const RgbImage& in) {
  GrayImage g;
  to_gray(in, &g);
  return g;
}

}  // namespace shle
