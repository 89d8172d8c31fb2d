// Interface between roi_align.cpp and its per-ISA bin kernels (roi_align_avx2.cpp,
// roi_align_avx512.cpp). Plain data and declarations only (cmake/isa.cmake).
#pragma once

namespace nn::detection {

// One bilinear sample: four source pixels (indexes into the map, y * width + x) and
// their weights; all-zero weights for samples outside the map.
struct RoiSample {
  int p[4];
  float w[4];
};

// One output bin over all channels: out[c] = (sum over samples s of w[0]*x[p[0]][c] +
// w[1]*x[p[1]][c] + w[2]*x[p[2]][c] + w[3]*x[p[3]][c]) / count, with x[p] = base +
// p * channels, summed in that order, as torchvision's CPU kernel does per channel.
struct RoiBin {
  const RoiSample* samples;
  int count_samples;
  const float* base;
  int channels;
  float count;
  float* out;
};

void roi_bin_scalar(const RoiBin& b);
void roi_bin_avx2(const RoiBin& b);
void roi_bin_avx512(const RoiBin& b);
void roi_bin_neon(const RoiBin& b);

}  // namespace nn::detection
