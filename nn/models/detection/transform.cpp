#include "nn/threads.h"
#include "nn/models/detection/transform.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "nn/error.h"
#include "nn/resize.h"

namespace nn::detection {

ImageSizes checked_input_size(int h, int w) {
  if (h < 32 || w < 32)
    throw Error("detector input is " + std::to_string(h) + "x" + std::to_string(w) +
                ", smaller than the minimum 32x32");
  if (h > 20000 || w > 20000)
    throw Error("detector input is " + std::to_string(h) + "x" + std::to_string(w) + ", larger than 20000 px");
  ImageSizes s;
  s.orig_h = h, s.orig_w = w;
  return s;
}

ImageSizes transform_sizes(int h, int w, const TransformConfig& cfg) {
  ImageSizes s = checked_input_size(h, w);
  const float lo = static_cast<float>(std::min(h, w)), hi = static_cast<float>(std::max(h, w));
  const float scale = std::min(static_cast<float>(cfg.min_size) / lo, static_cast<float>(cfg.max_size) / hi);
  s.resized_h = static_cast<int>(std::floor(static_cast<double>(h) * static_cast<double>(scale)));
  s.resized_w = static_cast<int>(std::floor(static_cast<double>(w) * static_cast<double>(scale)));
  const int d = cfg.size_divisible;
  s.padded_h = (s.resized_h + d - 1) / d * d;
  s.padded_w = (s.resized_w + d - 1) / d * d;
  return s;
}

void transform_image(const float* image, const ImageSizes& s, const TransformConfig& cfg, float* normalised,
                     float* resized, const TensorView& out) {
  const std::size_t plane = static_cast<std::size_t>(s.orig_h) * s.orig_w;
  // (x - mean) / std per element, as torchvision's NCHW normalisation rounds it,
  // written straight into NHWC for the resize kernel; rows split over the team (each
  // element is one subtraction and one division, so the split changes no bit).
  const long long rows = s.orig_h;
  parallel_for(rows, plane > 65536, [&](long long y_) {
    const long long y = static_cast<long long>(y_);
    const std::size_t i1 = static_cast<std::size_t>(y + 1) * s.orig_w;
    for (std::size_t i = static_cast<std::size_t>(y) * s.orig_w; i < i1; ++i)
      for (int c = 0; c < 3; ++c) normalised[i * 3 + c] = (image[c * plane + i] - cfg.mean[c]) / cfg.std[c];
  });
  resize_bilinear(ConstTensorView(normalised, {1, s.orig_h, s.orig_w, 3}),
                  TensorView{resized, {1, s.resized_h, s.resized_w, 3}});
  const std::size_t row = static_cast<std::size_t>(s.resized_w) * 3;
  parallel_for(out.shape.h, out.count() > 65536, [&](long long y_) {
    const int y = static_cast<int>(y_);
    float* dst = out.pixel(0, y, 0);
    const std::size_t copied = y < s.resized_h ? row : 0;
    if (copied) std::memcpy(dst, resized + y * row, sizeof(float) * copied);
    std::fill(dst + copied, dst + static_cast<std::size_t>(out.shape.w) * 3, 0.0f);  // padding = 0 after normalising
  });
}

}  // namespace nn::detection
