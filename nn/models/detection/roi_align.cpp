#include "nn/models/detection/roi_align.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

#include "nn/isa.h"
#include "nn/kernel_table.h"
#include "nn/models/detection/roi_align_bin.h"

namespace nn::detection {

namespace {

RoiSample sample_at(float y, float x, int height, int width) {
  RoiSample s{};
  if (y < -1.0f || y > height || x < -1.0f || x > width) return s;
  if (y <= 0) y = 0;
  if (x <= 0) x = 0;
  int y_low = static_cast<int>(y), x_low = static_cast<int>(x), y_high, x_high;
  if (y_low >= height - 1) {
    y_high = y_low = height - 1;
    y = static_cast<float>(y_low);
  } else {
    y_high = y_low + 1;
  }
  if (x_low >= width - 1) {
    x_high = x_low = width - 1;
    x = static_cast<float>(x_low);
  } else {
    x_high = x_low + 1;
  }
  const float ly = y - y_low, lx = x - x_low, hy = 1.0f - ly, hx = 1.0f - lx;
  s.w[0] = hy * hx, s.w[1] = hy * lx, s.w[2] = ly * hx, s.w[3] = ly * lx;
  s.p[0] = y_low * width + x_low, s.p[1] = y_low * width + x_high;
  s.p[2] = y_high * width + x_low, s.p[3] = y_high * width + x_high;
  return s;
}

}  // namespace

void roi_bin_scalar(const RoiBin& b) { roi_bin_with<float>(b); }

std::size_t roi_align_max_samples(const RoiAlignParams& p, float max_roi_h, float max_roi_w) {
  if (p.sampling_ratio > 0) return static_cast<std::size_t>(p.sampling_ratio) * p.sampling_ratio;
  const double gh = std::ceil(std::max(max_roi_h, 1.0f) / p.out_h) + 1, gw = std::ceil(std::max(max_roi_w, 1.0f) / p.out_w) + 1;
  return static_cast<std::size_t>(gh * gw);
}

void roi_align_one(const ConstTensorView& feature, int n, const Box& roi, const RoiAlignParams& p, float* out,
                   RoiSample* room, std::size_t sample_room) {
  const int height = feature.shape.h, width = feature.shape.w, channels = feature.shape.c;
  const float* base = feature.pixel(n, 0, 0);
  const float offset = p.aligned ? 0.5f : 0.0f;
  const float start_w = roi.x1 * p.spatial_scale - offset;
  const float start_h = roi.y1 * p.spatial_scale - offset;
  float roi_w = roi.x2 * p.spatial_scale - offset - start_w;
  float roi_h = roi.y2 * p.spatial_scale - offset - start_h;
  if (!p.aligned) {
    roi_w = std::max(roi_w, 1.0f);
    roi_h = std::max(roi_h, 1.0f);
  }
  const float bin_h = roi_h / static_cast<float>(p.out_h);
  const float bin_w = roi_w / static_cast<float>(p.out_w);
  const int grid_h = p.sampling_ratio > 0 ? p.sampling_ratio : static_cast<int>(std::ceil(roi_h / p.out_h));
  const int grid_w = p.sampling_ratio > 0 ? p.sampling_ratio : static_cast<int>(std::ceil(roi_w / p.out_w));
  const float count = static_cast<float>(std::max(grid_h * grid_w, 1));
  const std::size_t sample_count = static_cast<std::size_t>(grid_h) * grid_w;
  // The fixed 2 x 2 grid fits on the stack; adaptive sampling uses the caller's
  // planned room, the heap only for a one-off call without it.
  void (*bin_kernel)(const RoiBin&) = kernel_table(p.isa).roi_bin;
  RoiSample on_stack[16];
  std::vector<RoiSample> on_heap;
  RoiSample* samples = on_stack;
  if (room && sample_count <= sample_room) samples = room;
  else if (sample_count > 16) on_heap.resize(sample_count), samples = on_heap.data();
  RoiBin bin;
  bin.samples = samples;
  bin.count_samples = static_cast<int>(sample_count);
  bin.base = base;
  bin.channels = channels;
  bin.count = count;
  for (int ph = 0; ph < p.out_h; ++ph)
    for (int pw = 0; pw < p.out_w; ++pw) {
      std::size_t k = 0;
      for (int iy = 0; iy < grid_h; ++iy) {
        const float y = start_h + ph * bin_h + static_cast<float>(iy + .5f) * bin_h / static_cast<float>(grid_h);
        for (int ix = 0; ix < grid_w; ++ix) {
          const float x = start_w + pw * bin_w + static_cast<float>(ix + .5f) * bin_w / static_cast<float>(grid_w);
          samples[k++] = sample_at(y, x, height, width);
        }
      }
      // Channels innermost (NHWC): per channel the samples still add in torchvision's order.
      bin.out = out + (static_cast<std::size_t>(ph) * p.out_w + pw) * channels;
      bin_kernel(bin);
    }
}

}  // namespace nn::detection
