#include "nn/models/detection/detectron2_transform.h"

#include <algorithm>
#include <string>

#include "nn/error.h"
#include "nn/threads.h"

namespace nn::detection {

ImageSizes detectron2_sizes(int h, int w, const Detectron2TransformConfig& cfg) {
  ImageSizes s = checked_input_size(h, w);
  const double size = cfg.min_size;
  const double scale = size / std::min(h, w);
  double newh, neww;
  if (h < w)
    newh = size, neww = scale * w;
  else
    newh = scale * h, neww = size;
  if (std::max(newh, neww) > cfg.max_size) {
    const double shrink = cfg.max_size / std::max(newh, neww);
    newh *= shrink, neww *= shrink;
  }
  s.resized_h = static_cast<int>(newh + 0.5);
  s.resized_w = static_cast<int>(neww + 0.5);
  const int d = cfg.size_divisible;
  s.padded_h = (s.resized_h + d - 1) / d * d;
  s.padded_w = (s.resized_w + d - 1) / d * d;
  return s;
}

void Detectron2Transform::plan(const ImageSizes& sizes) {
  sizes_ = sizes;
  resize_.plan(sizes.orig_h, sizes.orig_w, sizes.resized_h, sizes.resized_w);
  resized_.resize(static_cast<std::size_t>(sizes.resized_h) * sizes.resized_w * 3);
}

void Detectron2Transform::run(const std::uint8_t* rgb, const Detectron2TransformConfig& cfg, const TensorView& out) {
  resize_.run(rgb, resized_.data());
  const ImageSizes& s = sizes_;
  parallel_for(out.shape.h, out.count() > 65536, [&](long long y_) {
    const int y = static_cast<int>(y_);
    float* dst = out.pixel(0, y, 0);
    int x = 0;
    if (y < s.resized_h) {
      const std::uint8_t* src = resized_.data() + static_cast<std::size_t>(y) * s.resized_w * 3;
      for (; x < s.resized_w; ++x)
        for (int c = 0; c < 3; ++c)  // channel c of BGR is channel 2 - c of RGB
          dst[3 * x + c] = (static_cast<float>(src[3 * x + 2 - c]) - cfg.mean[c]) / cfg.std[c];
    }
    std::fill(dst + 3 * x, dst + static_cast<std::size_t>(out.shape.w) * 3, 0.0f);
  });
}

}  // namespace nn::detection
