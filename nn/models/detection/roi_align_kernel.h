// Interface between roi_align.cpp and its per-ISA bin kernels (roi_align_avx2.cpp,
// roi_align_avx512.cpp). Plain data and declarations only (cmake/isa.cmake).
#pragma once

namespace nn::detection {

// Fixed sampling grids up to 4 x 4 per bin go through the kernels.
constexpr int kRoiBinMaxSamples = 16;

// One output bin over all channels: out[c] = (sum over samples s of
// w[4s]*v[4s][c] + w[4s+1]*v[4s+1][c] + w[4s+2]*v[4s+2][c] + w[4s+3]*v[4s+3][c]) / count,
// summed in that order, as torchvision's CPU kernel does per channel.
struct RoiBin {
  const float* v[4 * kRoiBinMaxSamples];
  float w[4 * kRoiBinMaxSamples];
  int samples;
  int channels;
  float count;
  float* out;
};

void roi_bin_scalar(const RoiBin& b);
void roi_bin_avx2(const RoiBin& b);
void roi_bin_avx512(const RoiBin& b);

}  // namespace nn::detection
