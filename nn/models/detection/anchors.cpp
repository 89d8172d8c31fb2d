#include "nn/models/detection/anchors.h"

#include <cmath>

namespace nn::detection {

std::vector<Box> cell_anchors(const std::vector<float>& sizes, const std::vector<float>& ratios) {
  std::vector<Box> out;
  for (float r : ratios) {
    // float32 tensor maths as in generate_anchors: h_ratio = sqrt(r), w_ratio = 1 / h_ratio.
    const float h_ratio = std::sqrt(r);
    const float w_ratio = 1.0f / h_ratio;
    for (float s : sizes) {
      const float ws = w_ratio * s, hs = h_ratio * s;
      out.push_back({std::nearbyint(-ws / 2.0f), std::nearbyint(-hs / 2.0f), std::nearbyint(ws / 2.0f),
                     std::nearbyint(hs / 2.0f)});
    }
  }
  return out;
}

std::vector<Box> cell_anchors_unrounded(const std::vector<float>& sizes, const std::vector<float>& ratios) {
  std::vector<Box> out;
  for (float s : sizes)
    for (float r : ratios) {
      const double area = static_cast<double>(s) * s;
      const double w = std::sqrt(area / r), h = r * w;
      out.push_back({static_cast<float>(-w / 2.0), static_cast<float>(-h / 2.0), static_cast<float>(w / 2.0),
                     static_cast<float>(h / 2.0)});
    }
  return out;
}

std::vector<Box> grid_anchors(const std::vector<Box>& cell, int grid_h, int grid_w, int padded_h, int padded_w) {
  return grid_anchors_strided(cell, grid_h, grid_w, padded_h / grid_h, padded_w / grid_w);
}

std::vector<Box> grid_anchors_strided(const std::vector<Box>& cell, int grid_h, int grid_w, int stride_h,
                                      int stride_w) {
  std::vector<Box> out;
  out.reserve(static_cast<std::size_t>(grid_h) * grid_w * cell.size());
  for (int y = 0; y < grid_h; ++y)
    for (int x = 0; x < grid_w; ++x) {
      const float sx = static_cast<float>(x * stride_w), sy = static_cast<float>(y * stride_h);
      for (const Box& a : cell) out.push_back({sx + a.x1, sy + a.y1, sx + a.x2, sy + a.y2});
    }
  return out;
}

}  // namespace nn::detection
