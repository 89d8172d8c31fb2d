// AVX-512 LayerNorm over rows of c floats, four rows at a time.
//
// Per row, in a fixed order that depends only on c:
//   pass 1: two vector accumulators take the 16-wide chunks alternately (the masked
//           tail chunk goes to the second), then their sum is folded 16 -> 1 by halves;
//           m = sum / c.
//   pass 2: the same for d^2 (FMA) and for d, d = x - m. The float m is off the true
//           mean by up to half an ulp of |mean|, which for rows whose mean is large
//           against their spread would dominate the error; delta = sum(d) / c recovers
//           that offset ("corrected two-pass"), var = (sum(d^2) - c delta^2) / c.
//   pass 3: y = ((x - m) - delta) * rstd * gamma + beta, rstd = 1 / sqrt(var + eps).
// The four rows' folds share shuffles (that is what the grouping buys); the adds
// each row sees are the same as if it were alone, and a short group repeats its
// last row, so results never depend on which rows are processed together.
#include <immintrin.h>

#include <cstddef>

#include "nn/layernorm_kernel.h"

// GCC 12's AVX-512 headers build masked intrinsics on a self-initialised
// "undefined" vector, which -Wmaybe-uninitialized reports at every inlined use.
#pragma GCC diagnostic ignored "-Wuninitialized"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"

namespace nn {
namespace {

constexpr int L = 16;

// Sums of four vectors, each folded by halves: 512 -> 256 -> 128 -> 64 -> 32 bits.
inline __m128 fold4(__m512 a, __m512 b, __m512 c, __m512 d) {
  const __m512 ab = _mm512_add_ps(_mm512_shuffle_f32x4(a, b, _MM_SHUFFLE(1, 0, 1, 0)),
                                  _mm512_shuffle_f32x4(a, b, _MM_SHUFFLE(3, 2, 3, 2)));
  const __m512 cd = _mm512_add_ps(_mm512_shuffle_f32x4(c, d, _MM_SHUFFLE(1, 0, 1, 0)),
                                  _mm512_shuffle_f32x4(c, d, _MM_SHUFFLE(3, 2, 3, 2)));
  // 128-bit lane k now holds row k's 4-float partial: [a, b, c, d].
  const __m512 s = _mm512_add_ps(_mm512_shuffle_f32x4(ab, cd, _MM_SHUFFLE(2, 0, 2, 0)),
                                 _mm512_shuffle_f32x4(ab, cd, _MM_SHUFFLE(3, 1, 3, 1)));
  const __m512 t = _mm512_add_ps(s, _mm512_permute_ps(s, _MM_SHUFFLE(1, 0, 3, 2)));
  const __m512 u = _mm512_add_ps(t, _mm512_permute_ps(t, _MM_SHUFFLE(2, 3, 0, 1)));
  const __m512i first = _mm512_setr_epi32(0, 4, 8, 12, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0);
  return _mm512_castps512_ps128(_mm512_permutexvar_ps(first, u));
}

void group(const float* const* x, float* const* y, int nstore, int c, const float* gamma,
           const float* beta, float eps) {
  const int full = c / L;
  const int tail = c % L;
  const __mmask16 mask = static_cast<__mmask16>((1u << tail) - 1u);
  const __m128 cf = _mm_set1_ps(static_cast<float>(c));

  // Pass 1: provisional mean m.
  __m512 a0[4], a1[4];
  for (int r = 0; r < 4; ++r) a0[r] = a1[r] = _mm512_setzero_ps();
  int v = 0;
  for (; v + 2 <= full; v += 2)
    for (int r = 0; r < 4; ++r) {
      a0[r] = _mm512_add_ps(a0[r], _mm512_loadu_ps(x[r] + v * L));
      a1[r] = _mm512_add_ps(a1[r], _mm512_loadu_ps(x[r] + v * L + L));
    }
  if (v < full)
    for (int r = 0; r < 4; ++r) a0[r] = _mm512_add_ps(a0[r], _mm512_loadu_ps(x[r] + v * L));
  if (tail)
    for (int r = 0; r < 4; ++r)
      a1[r] = _mm512_add_ps(a1[r], _mm512_maskz_loadu_ps(mask, x[r] + full * L));
  const __m128 m4 = _mm_div_ps(
      fold4(_mm512_add_ps(a0[0], a1[0]), _mm512_add_ps(a0[1], a1[1]),
            _mm512_add_ps(a0[2], a1[2]), _mm512_add_ps(a0[3], a1[3])),
      cf);
  alignas(16) float mean[4];
  _mm_store_ps(mean, m4);

  // Pass 2: sums of d = x - m and of d^2.
  __m512 m[4], e[4];
  for (int r = 0; r < 4; ++r) {
    m[r] = _mm512_set1_ps(mean[r]);
    a0[r] = a1[r] = e[r] = _mm512_setzero_ps();
  }
  v = 0;
  for (; v + 2 <= full; v += 2)
    for (int r = 0; r < 4; ++r) {
      const __m512 d0 = _mm512_sub_ps(_mm512_loadu_ps(x[r] + v * L), m[r]);
      const __m512 d1 = _mm512_sub_ps(_mm512_loadu_ps(x[r] + v * L + L), m[r]);
      a0[r] = _mm512_fmadd_ps(d0, d0, a0[r]);
      a1[r] = _mm512_fmadd_ps(d1, d1, a1[r]);
      e[r] = _mm512_add_ps(e[r], _mm512_add_ps(d0, d1));
    }
  if (v < full)
    for (int r = 0; r < 4; ++r) {
      const __m512 d0 = _mm512_sub_ps(_mm512_loadu_ps(x[r] + v * L), m[r]);
      a0[r] = _mm512_fmadd_ps(d0, d0, a0[r]);
      e[r] = _mm512_add_ps(e[r], d0);
    }
  if (tail)
    for (int r = 0; r < 4; ++r) {
      const __m512 d1 =
          _mm512_maskz_sub_ps(mask, _mm512_maskz_loadu_ps(mask, x[r] + full * L), m[r]);
      a1[r] = _mm512_fmadd_ps(d1, d1, a1[r]);
      e[r] = _mm512_add_ps(e[r], d1);
    }
  const __m128 delta4 = _mm_div_ps(fold4(e[0], e[1], e[2], e[3]), cf);
  const __m128 sq4 = fold4(_mm512_add_ps(a0[0], a1[0]), _mm512_add_ps(a0[1], a1[1]),
                           _mm512_add_ps(a0[2], a1[2]), _mm512_add_ps(a0[3], a1[3]));
  const __m128 var4 = _mm_max_ps(
      _mm_div_ps(_mm_sub_ps(sq4, _mm_mul_ps(_mm_mul_ps(delta4, delta4), cf)), cf), _mm_setzero_ps());
  const __m128 rstd4 =
      _mm_div_ps(_mm_set1_ps(1.0f), _mm_sqrt_ps(_mm_add_ps(var4, _mm_set1_ps(eps))));
  alignas(16) float rstd[4], delta[4];
  _mm_store_ps(rstd, rstd4);
  _mm_store_ps(delta, delta4);

  // Pass 3: y = ((x - m) - delta) * rstd * gamma + beta.
  const __m512 one = _mm512_set1_ps(1.0f);
  const __m512 zero = _mm512_setzero_ps();
  for (int r = 0; r < nstore; ++r) {
    const __m512 s = _mm512_set1_ps(rstd[r]);
    const __m512 dl = _mm512_set1_ps(delta[r]);
    const float* xr = x[r];
    float* yr = y[r];
    for (v = 0; v < full; ++v) {
      const __m512 g = gamma ? _mm512_loadu_ps(gamma + v * L) : one;
      const __m512 b = beta ? _mm512_loadu_ps(beta + v * L) : zero;
      const __m512 d = _mm512_sub_ps(_mm512_sub_ps(_mm512_loadu_ps(xr + v * L), m[r]), dl);
      _mm512_storeu_ps(yr + v * L, _mm512_fmadd_ps(_mm512_mul_ps(d, s), g, b));
    }
    if (tail) {
      const __m512 g = gamma ? _mm512_maskz_loadu_ps(mask, gamma + full * L) : one;
      const __m512 b = beta ? _mm512_maskz_loadu_ps(mask, beta + full * L) : zero;
      const __m512 d =
          _mm512_sub_ps(_mm512_sub_ps(_mm512_maskz_loadu_ps(mask, xr + full * L), m[r]), dl);
      _mm512_mask_storeu_ps(yr + full * L, mask, _mm512_fmadd_ps(_mm512_mul_ps(d, s), g, b));
    }
  }
}

}  // namespace

void layernorm_rows_avx512(std::size_t rows, int c, const float* x, std::ptrdiff_t ldx, float* y,
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
    group(xs, ys, n, c, gamma, beta, eps);
  }
}

}  // namespace nn
