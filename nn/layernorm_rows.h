// The LayerNorm row kernel of nn/layernorm_kernel.h, written once over a per-ISA "vector
// ops" trait Ops (nn/arch/x86/vecops_avx2.h, vecops_avx512.h, nn/arch/arm/vecops_neon.h;
// L = Ops::kLanes floats per vector), in an anonymous namespace: each ISA file
// (nn/arch/*/layernorm_*.cpp) instantiates it with its own flags in a few lines.
//
// Rows of c floats, four rows at a time. Per row, in a fixed order that depends only on
// c and L:
//   pass 1: two vector accumulators take the L-wide chunks alternately (the masked
//           tail chunk goes to the second), then their sum is folded L -> 1 by halves
//           (Ops::fold4); m = sum / c.
//   pass 2: the same for d^2 (FMA) and for d, d = x - m. The float m is off the true
//           mean by up to half an ulp of |mean|, which for rows whose mean is large
//           against their spread would dominate the error; delta = sum(d) / c recovers
//           that offset ("corrected two-pass"), var = (sum(d^2) - c delta^2) / c.
//   pass 3: y = ((x - m) - delta) * rstd * gamma + beta, rstd = 1 / sqrt(var + eps).
// The four rows' folds share shuffles (that is what the grouping buys); the adds
// each row sees are the same as if it were alone, and a short group repeats its
// last row, so results never depend on which rows are processed together.
#pragma once

#include <cstddef>

#include "nn/layernorm_kernel.h"

namespace nn {
namespace {

template <class Ops>
void layernorm_group(const float* const* x, float* const* y, int nstore, int c,
                     const float* gamma, const float* beta, float eps) {
  using V = typename Ops::V;
  using V4 = typename Ops::V4;  // the four rows' statistics, one lane each
  constexpr int L = Ops::kLanes;
  const int full = c / L;
  const int tail = c % L;
  const typename Ops::Mask mask = Ops::mask(tail);
  const float cf = static_cast<float>(c);

  // Pass 1: provisional mean m.
  V a0[4], a1[4];
  for (int r = 0; r < 4; ++r) a0[r] = a1[r] = Ops::zero();
  int v = 0;
  for (; v + 2 <= full; v += 2)
    for (int r = 0; r < 4; ++r) {
      a0[r] = Ops::add(a0[r], Ops::loadu(x[r] + v * L));
      a1[r] = Ops::add(a1[r], Ops::loadu(x[r] + v * L + L));
    }
  if (v < full)
    for (int r = 0; r < 4; ++r) a0[r] = Ops::add(a0[r], Ops::loadu(x[r] + v * L));
  if (tail)
    for (int r = 0; r < 4; ++r) a1[r] = Ops::add(a1[r], Ops::load_part(x[r] + full * L, mask));
  const V4 m4 = Ops::fold4(Ops::add(a0[0], a1[0]), Ops::add(a0[1], a1[1]),
                          Ops::add(a0[2], a1[2]), Ops::add(a0[3], a1[3])) /
                cf;
  alignas(16) float mean[4];
  __builtin_memcpy(mean, &m4, sizeof(mean));

  // Pass 2: sums of d = x - m and of d^2.
  V m[4], e[4];
  for (int r = 0; r < 4; ++r) {
    m[r] = Ops::set1(mean[r]);
    a0[r] = a1[r] = e[r] = Ops::zero();
  }
  v = 0;
  for (; v + 2 <= full; v += 2)
    for (int r = 0; r < 4; ++r) {
      const V d0 = Ops::sub(Ops::loadu(x[r] + v * L), m[r]);
      const V d1 = Ops::sub(Ops::loadu(x[r] + v * L + L), m[r]);
      a0[r] = Ops::fma(d0, d0, a0[r]);
      a1[r] = Ops::fma(d1, d1, a1[r]);
      e[r] = Ops::add(e[r], Ops::add(d0, d1));
    }
  if (v < full)
    for (int r = 0; r < 4; ++r) {
      const V d0 = Ops::sub(Ops::loadu(x[r] + v * L), m[r]);
      a0[r] = Ops::fma(d0, d0, a0[r]);
      e[r] = Ops::add(e[r], d0);
    }
  if (tail)
    for (int r = 0; r < 4; ++r) {
      const V d1 = Ops::keep(mask, Ops::sub(Ops::load_part(x[r] + full * L, mask), m[r]));
      a1[r] = Ops::fma(d1, d1, a1[r]);
      e[r] = Ops::add(e[r], d1);
    }
  const V4 delta4 = Ops::fold4(e[0], e[1], e[2], e[3]) / cf;
  const V4 sq4 = Ops::fold4(Ops::add(a0[0], a1[0]), Ops::add(a0[1], a1[1]),
                            Ops::add(a0[2], a1[2]), Ops::add(a0[3], a1[3]));
  const V4 var4 = Ops::max4((sq4 - (delta4 * delta4) * cf) / cf, V4{});
  const V4 rstd4 = 1.0f / Ops::sqrt4(var4 + eps);
  alignas(16) float rstd[4], delta[4];
  __builtin_memcpy(rstd, &rstd4, sizeof(rstd));
  __builtin_memcpy(delta, &delta4, sizeof(delta));

  // Pass 3: y = ((x - m) - delta) * rstd * gamma + beta.
  const V one = Ops::set1(1.0f);
  const V zero = Ops::zero();
  for (int r = 0; r < nstore; ++r) {
    const V s = Ops::set1(rstd[r]);
    const V dl = Ops::set1(delta[r]);
    const float* xr = x[r];
    float* yr = y[r];
    for (v = 0; v < full; ++v) {
      const V g = gamma ? Ops::loadu(gamma + v * L) : one;
      const V b = beta ? Ops::loadu(beta + v * L) : zero;
      const V d = Ops::sub(Ops::sub(Ops::loadu(xr + v * L), m[r]), dl);
      Ops::storeu(yr + v * L, Ops::fma(Ops::mul(d, s), g, b));
    }
    if (tail) {
      const V g = gamma ? Ops::load_part(gamma + full * L, mask) : one;
      const V b = beta ? Ops::load_part(beta + full * L, mask) : zero;
      const V d = Ops::sub(Ops::sub(Ops::load_part(xr + full * L, mask), m[r]), dl);
      Ops::store_part(yr + full * L, mask, Ops::fma(Ops::mul(d, s), g, b));
    }
  }
}

// The entry point of every ISA: groups of four rows, a short last group padded with
// repeats of its last row whose results are not stored.
template <class Ops>
void layernorm_rows_with(std::size_t rows, int c, const float* x, std::ptrdiff_t ldx, float* y,
                         std::ptrdiff_t ldy, const float* gamma, const float* beta, float eps) {
  for (std::size_t r0 = 0; r0 < rows; r0 += 4) {
    const int n = rows - r0 < 4 ? static_cast<int>(rows - r0) : 4;
    const float* xs[4];
    float* ys[4];
    for (int r = 0; r < 4; ++r) {
      const std::size_t row = r0 + (r < n ? r : n - 1);
      xs[r] = x + static_cast<std::ptrdiff_t>(row) * ldx;
      ys[r] = y + static_cast<std::ptrdiff_t>(row) * ldy;
    }
    layernorm_group<Ops>(xs, ys, n, c, gamma, beta, eps);
  }
}

}  // namespace
}  // namespace nn
