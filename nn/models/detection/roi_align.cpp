#include "nn/models/detection/roi_align.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

#include "nn/isa.h"
#include "nn/models/detection/roi_align_bin.h"

namespace nn::detection {

namespace {

// One bilinear sample: four source pixels and their weights; all-zero weights for
// samples outside the map (roi_align_common.h's bilinear_interpolate rules).
struct Sample {
  int p1 = 0, p2 = 0, p3 = 0, p4 = 0;
  float w1 = 0, w2 = 0, w3 = 0, w4 = 0;
};

Sample sample_at(float y, float x, int height, int width) {
  Sample s;
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
  s.w1 = hy * hx, s.w2 = hy * lx, s.w3 = ly * hx, s.w4 = ly * lx;
  s.p1 = y_low * width + x_low, s.p2 = y_low * width + x_high;
  s.p3 = y_high * width + x_low, s.p4 = y_high * width + x_high;
  return s;
}

}  // namespace

void roi_bin_scalar(const RoiBin& b) { roi_bin_with<float>(b); }

void roi_align_one(const ConstTensorView& feature, int n, const Box& roi, const RoiAlignParams& p, float* out) {
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
  // Grids of up to kRoiBinMaxSamples samples (the models' fixed 2 x 2) go through the
  // ISA's bin kernel; only adaptive sampling of large RoIs needs the heap and the
  // scalar kernel, bin by bin on the same arithmetic.
  void (*bin_kernel)(const RoiBin&) = roi_bin_scalar;
  if (active_isa() == Isa::Avx512) bin_kernel = roi_bin_avx512;
  else if (active_isa() == Isa::Avx2) bin_kernel = roi_bin_avx2;
  Sample on_stack[kRoiBinMaxSamples];
  std::vector<Sample> on_heap;
  Sample* samples = on_stack;
  if (sample_count > kRoiBinMaxSamples) on_heap.resize(sample_count), samples = on_heap.data();
  RoiBin bin;
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
      float* o = out + (static_cast<std::size_t>(ph) * p.out_w + pw) * channels;
      bin.out = o;
      if (sample_count <= kRoiBinMaxSamples) {
        for (std::size_t s = 0; s < sample_count; ++s) {
          const Sample& sm = samples[s];
          const int px[4] = {sm.p1, sm.p2, sm.p3, sm.p4};
          const float w[4] = {sm.w1, sm.w2, sm.w3, sm.w4};
          for (int j = 0; j < 4; ++j) {
            bin.v[4 * s + j] = base + static_cast<std::size_t>(px[j]) * channels;
            bin.w[4 * s + j] = w[j];
          }
        }
        bin.samples = static_cast<int>(sample_count);
        bin_kernel(bin);
        continue;
      }
      std::fill(o, o + channels, 0.0f);
      for (std::size_t k2 = 0; k2 < sample_count; ++k2) {
        const Sample& s = samples[k2];
        const float* v1 = base + static_cast<std::size_t>(s.p1) * channels;
        const float* v2 = base + static_cast<std::size_t>(s.p2) * channels;
        const float* v3 = base + static_cast<std::size_t>(s.p3) * channels;
        const float* v4 = base + static_cast<std::size_t>(s.p4) * channels;
        for (int c = 0; c < channels; ++c) o[c] += s.w1 * v1[c] + s.w2 * v2[c] + s.w3 * v3[c] + s.w4 * v4[c];
      }
      for (int c = 0; c < channels; ++c) o[c] /= count;
    }
}

}  // namespace nn::detection
