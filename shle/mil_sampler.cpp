#include "shle/mil_sampler.h"

#include <algorithm>
#include <cstddef>

namespace shle {

void mil_sample(int rows, int cols, int x, int y, int w, int h, float inrad, float outrad, int maxnum,
                CvRng* rng, std::vector<MilWindow>* out) {
  out->clear();
  // OpenCV works on the integral image, one row and column larger: its
  // (rows + 1) - h - 1 - 1 is our rows - h - 1.
  const int r_in = static_cast<int>(inrad);
  const int min_row = std::max(0, y - r_in), max_row = std::min(rows - h - 1, y + r_in);
  const int min_col = std::max(0, x - r_in), max_col = std::min(cols - w - 1, x + r_in);
  // An empty rectangle: OpenCV draws nothing then (and throws for a negative
  // size); no window either way.
  if (max_row < min_row || max_col < min_col) return;
  const std::size_t candidates =
      static_cast<std::size_t>(max_row - min_row + 1) * static_cast<std::size_t>(max_col - min_col + 1);
  const float prob = static_cast<float>(maxnum) / static_cast<float>(candidates);
  const float in2 = inrad * inrad, out2 = outrad * outrad;
  for (int r = min_row; r <= max_row; ++r)
    for (int c = min_col; c <= max_col; ++c) {
      const int dist = (y - r) * (y - r) + (x - c) * (x - c);
      const float u = rng->uniform01();
      if (u < prob && static_cast<float>(dist) < in2 && static_cast<float>(dist) >= out2)
        out->push_back(MilWindow{c, r});
    }
  if (out->size() > static_cast<std::size_t>(std::max(0, maxnum))) out->resize(static_cast<std::size_t>(maxnum));
}

}  // namespace shle
