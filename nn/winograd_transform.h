// The F(4x4, 3x3) Winograd input and output transforms, written once over a value type
// V that is a float (the scalar path and every ISA's channel tail) or a GCC vector of
// floats (nn/winograd_avx2.cpp, nn/winograd_avx512.cpp). Every helper lives in an
// anonymous namespace, so each including file compiles its own copy with its own ISA
// flags (cmake/isa.cmake). With -ffp-contract=off the same operations in the same order
// give the same bits in every copy: the transforms never differ between ISAs.
//
// Interpolation points 0, +-1, +-2 and infinity (Lavin and Gray, 2016):
//   B^T = [4  0 -5  0  1  0]    A^T = [1  1  1  1  1  0]
//         [0 -4 -4  1  1  0]          [0  1 -1  2 -2  0]
//         [0  4 -4 -1  1  0]          [0  1  1  4  4  0]
//         [0 -2 -1  2  1  0]          [0  1 -1  8 -8  1]
//         [0  2 -1 -2  1  0]
//         [0  4  0 -5  0  1]
// V = B^T d B of a 6x6 input patch d, Y = A^T M A of the 6x6 products M (4x4 outputs);
// the weight transform G g G^T is done once at load, in double (nn/winograd.cpp).
#pragma once

#include <cstddef>

#include "nn/winograd_kernel.h"

namespace nn {
namespace {

// B^T applied to d[0], d[s], ..., d[5s], written to r[0], r[rs], ..., r[5rs].
template <class V>
inline void winograd_bt(const V* d, int s, V* r, int rs) {
  const V d0 = d[0], d1 = d[s], d2 = d[2 * s], d3 = d[3 * s], d4 = d[4 * s], d5 = d[5 * s];
  const V four = V{} + 4.0f, five = V{} + 5.0f, two = V{} + 2.0f;
  r[0] = (four * d0 - five * d2) + d4;
  r[rs] = (d3 + d4) - four * (d1 + d2);
  r[2 * rs] = (d4 - d3) + four * (d1 - d2);
  r[3 * rs] = (d4 - d2) + two * (d3 - d1);
  r[4 * rs] = (d4 - d2) - two * (d3 - d1);
  r[5 * rs] = (four * d1 - five * d3) + d5;
}

// A^T applied to m[0], m[s], ..., m[5s], written to y[0], y[ys], y[2ys], y[3ys].
template <class V>
inline void winograd_at(const V* m, int s, V* y, int ys) {
  const V a = m[s] + m[2 * s], b = m[s] - m[2 * s];
  const V c = m[3 * s] + m[4 * s], d = m[3 * s] - m[4 * s];
  const V two = V{} + 2.0f, four = V{} + 4.0f, eight = V{} + 8.0f;
  y[0] = (m[0] + a) + c;
  y[ys] = b + two * d;
  y[2 * ys] = a + four * c;
  y[3 * ys] = (b + eight * d) + m[5 * s];
}

// Loads and stores of V: Io<V>::load(p) reads the value of type V at p (unaligned).
template <class V>
struct WinogradIo {
  static V load(const float* p) {
    V v;
    __builtin_memcpy(&v, p, sizeof(V));
    return v;
  }
  static void store(float* p, V v) { __builtin_memcpy(p, &v, sizeof(V)); }
  static constexpr int lanes = sizeof(V) / sizeof(float);
};

// Channels [c0, c1) of one tile's input transform, L = lanes of V at a time.
template <class V>
void winograd_channels(const WinogradInputTile& t, int c0, int c1) {
  using Io = WinogradIo<V>;
  for (int ch = c0; ch + Io::lanes <= c1; ch += Io::lanes) {
    V d[36], u[36];
    for (int i = 0; i < 36; ++i) d[i] = Io::load(t.src[i] + ch);
    for (int x = 0; x < 6; ++x) winograd_bt(d + x, 6, u + x, 6);     // along y, per column
    for (int y = 0; y < 6; ++y) winograd_bt(u + 6 * y, 1, d + 6 * y, 1);  // along x, per row
    for (int i = 0; i < 36; ++i) Io::store(t.v + i * t.xi_stride + ch, d[i]);
  }
}

// Channels [c0, c1) of one tile's output transform and epilogue.
template <class V>
void winograd_channels(const WinogradOutputTile& t, int c0, int c1) {
  using Io = WinogradIo<V>;
  for (int ch = c0; ch + Io::lanes <= c1; ch += Io::lanes) {
    V m[36], s[24], y[16];
    for (int i = 0; i < 36; ++i) m[i] = Io::load(t.m + i * t.xi_stride + ch);
    for (int x = 0; x < 6; ++x) winograd_at(m + x, 6, s + x, 6);      // along y, per column
    for (int r = 0; r < 4; ++r) winograd_at(s + 6 * r, 1, y + 4 * r, 1);  // along x, per row
    const V bias = t.bias ? Io::load(t.bias + ch) : V{};
    const V zero = V{};
    for (int p = 0; p < 16; ++p) {
      if (!t.dst[p]) continue;
      V v = y[p] + bias;
      if (t.relu_before) v = v < zero ? zero : v;  // NaN stays NaN, as torch.relu
      if (t.res[p]) v = v + Io::load(t.res[p] + ch);
      if (t.relu_after) v = v < zero ? zero : v;
      Io::store(t.dst[p] + ch, v);
    }
  }
}

// A whole tile (input or output): full vectors of V, then the channel tail one float
// at a time.
template <class V, class Tile>
void winograd_tile_with(const Tile& t) {
  constexpr int L = WinogradIo<V>::lanes;
  const int full = t.c / L * L;
  winograd_channels<V>(t, 0, full);
  if (full < t.c) winograd_channels<float>(t, full, t.c);
}

}  // namespace
}  // namespace nn
