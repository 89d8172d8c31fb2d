// Interface between nn/winograd.cpp (packing, tiling, threading) and the transform
// kernels of nn/winograd_avx2.cpp / nn/winograd_avx512.cpp. Plain data and
// declarations only: the ISA files include it (cmake/isa.cmake).
#pragma once

#include <cstddef>

namespace nn {

// One 4x4 output tile's input transform: the 36 pixels of its 6x6 input patch
// (src[y * 6 + x] -> channel 0 of that pixel, or of a zero row outside the image),
// transformed for channels [0, c) into v[xi * xi_stride + channel], xi = 0..35.
struct WinogradInputTile {
  const float* src[36];
  int c;
  float* v;
  std::ptrdiff_t xi_stride;
};

// One tile's output transform: the 36 products m[xi * xi_stride + channel] for
// channels [0, c) -> 16 output pixels dst[y * 4 + x] (null: outside the image) with
// v = Y + bias; relu_before: v = max(v, 0); v += res[p] (when res[p] is set);
// relu_after: v = max(v, 0).
struct WinogradOutputTile {
  const float* m;
  std::ptrdiff_t xi_stride;
  int c;
  float* dst[16];
  const float* res[16];
  const float* bias;  // [c] or null
  bool relu_before, relu_after;
};

// The scalar transforms (nn/winograd.cpp) are the reference the ISA versions are tested
// against: the same operations in the same order, so the same bits.
void winograd_input_tile_scalar(const WinogradInputTile& t);
void winograd_output_tile_scalar(const WinogradOutputTile& t);
void winograd_input_tile_avx512(const WinogradInputTile& t);
void winograd_output_tile_avx512(const WinogradOutputTile& t);
void winograd_input_tile_avx2(const WinogradInputTile& t);
void winograd_input_tile_neon(const WinogradInputTile& t);
void winograd_output_tile_neon(const WinogradOutputTile& t);
void winograd_output_tile_avx2(const WinogradOutputTile& t);

}  // namespace nn
