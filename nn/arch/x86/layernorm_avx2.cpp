// AVX2 LayerNorm over rows of c floats, four rows at a time: the scheme of
// layernorm_avx512.cpp (see there) with 8-wide chunks, folded 8 -> 1 by halves.
#include <immintrin.h>

#include <cstddef>

#include "nn/layernorm_kernel.h"

namespace nn {
namespace {

constexpr int L = 8;

// Sums of four vectors, each folded by halves: 256 -> 128 -> 64 -> 32 bits.
inline __m128 fold4(__m256 a, __m256 b, __m256 c, __m256 d) {
  const __m256 ab =
      _mm256_add_ps(_mm256_permute2f128_ps(a, b, 0x20), _mm256_permute2f128_ps(a, b, 0x31));
  const __m256 cd =
      _mm256_add_ps(_mm256_permute2f128_ps(c, d, 0x20), _mm256_permute2f128_ps(c, d, 0x31));
  // Lanes: [a0+a2, a1+a3, c0+c2, c1+c3 | b0+b2, b1+b3, d0+d2, d1+d3].
  const __m256 s = _mm256_add_ps(_mm256_shuffle_ps(ab, cd, _MM_SHUFFLE(1, 0, 1, 0)),
                                 _mm256_shuffle_ps(ab, cd, _MM_SHUFFLE(3, 2, 3, 2)));
  // Lanes: [a, c, a, c | b, d, b, d].
  const __m256 t = _mm256_add_ps(_mm256_shuffle_ps(s, s, _MM_SHUFFLE(2, 0, 2, 0)),
                                 _mm256_shuffle_ps(s, s, _MM_SHUFFLE(3, 1, 3, 1)));
  return _mm_unpacklo_ps(_mm256_castps256_ps128(t), _mm256_extractf128_ps(t, 1));
}

void group(const float* const* x, float* const* y, int nstore, int c, const float* gamma,
           const float* beta, float eps) {
  const int full = c / L;
  const int tail = c % L;
  const __m256i mask =
      _mm256_cmpgt_epi32(_mm256_set1_epi32(tail), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
  const __m128 cf = _mm_set1_ps(static_cast<float>(c));

  // Pass 1: provisional mean m.
  __m256 a0[4], a1[4];
  for (int r = 0; r < 4; ++r) a0[r] = a1[r] = _mm256_setzero_ps();
  int v = 0;
  for (; v + 2 <= full; v += 2)
    for (int r = 0; r < 4; ++r) {
      a0[r] = _mm256_add_ps(a0[r], _mm256_loadu_ps(x[r] + v * L));
      a1[r] = _mm256_add_ps(a1[r], _mm256_loadu_ps(x[r] + v * L + L));
    }
  if (v < full)
    for (int r = 0; r < 4; ++r) a0[r] = _mm256_add_ps(a0[r], _mm256_loadu_ps(x[r] + v * L));
  if (tail)
    for (int r = 0; r < 4; ++r)
      a1[r] = _mm256_add_ps(a1[r], _mm256_maskload_ps(x[r] + full * L, mask));
  const __m128 m4 = _mm_div_ps(
      fold4(_mm256_add_ps(a0[0], a1[0]), _mm256_add_ps(a0[1], a1[1]),
            _mm256_add_ps(a0[2], a1[2]), _mm256_add_ps(a0[3], a1[3])),
      cf);
  alignas(16) float mean[4];
  _mm_store_ps(mean, m4);

  // Pass 2: sums of d = x - m and of d^2.
  __m256 m[4], e[4];
  for (int r = 0; r < 4; ++r) {
    m[r] = _mm256_set1_ps(mean[r]);
    a0[r] = a1[r] = e[r] = _mm256_setzero_ps();
  }
  v = 0;
  for (; v + 2 <= full; v += 2)
    for (int r = 0; r < 4; ++r) {
      const __m256 d0 = _mm256_sub_ps(_mm256_loadu_ps(x[r] + v * L), m[r]);
      const __m256 d1 = _mm256_sub_ps(_mm256_loadu_ps(x[r] + v * L + L), m[r]);
      a0[r] = _mm256_fmadd_ps(d0, d0, a0[r]);
      a1[r] = _mm256_fmadd_ps(d1, d1, a1[r]);
      e[r] = _mm256_add_ps(e[r], _mm256_add_ps(d0, d1));
    }
  if (v < full)
    for (int r = 0; r < 4; ++r) {
      const __m256 d0 = _mm256_sub_ps(_mm256_loadu_ps(x[r] + v * L), m[r]);
      a0[r] = _mm256_fmadd_ps(d0, d0, a0[r]);
      e[r] = _mm256_add_ps(e[r], d0);
    }
  if (tail)
    for (int r = 0; r < 4; ++r) {
      const __m256 d1 = _mm256_and_ps(
          _mm256_castsi256_ps(mask), _mm256_sub_ps(_mm256_maskload_ps(x[r] + full * L, mask), m[r]));
      a1[r] = _mm256_fmadd_ps(d1, d1, a1[r]);
      e[r] = _mm256_add_ps(e[r], d1);
    }
  const __m128 delta4 = _mm_div_ps(fold4(e[0], e[1], e[2], e[3]), cf);
  const __m128 sq4 = fold4(_mm256_add_ps(a0[0], a1[0]), _mm256_add_ps(a0[1], a1[1]),
                           _mm256_add_ps(a0[2], a1[2]), _mm256_add_ps(a0[3], a1[3]));
  const __m128 var4 = _mm_max_ps(
      _mm_div_ps(_mm_sub_ps(sq4, _mm_mul_ps(_mm_mul_ps(delta4, delta4), cf)), cf), _mm_setzero_ps());
  const __m128 rstd4 =
      _mm_div_ps(_mm_set1_ps(1.0f), _mm_sqrt_ps(_mm_add_ps(var4, _mm_set1_ps(eps))));
  alignas(16) float rstd[4], delta[4];
  _mm_store_ps(rstd, rstd4);
  _mm_store_ps(delta, delta4);

  // Pass 3: y = ((x - m) - delta) * rstd * gamma + beta.
  const __m256 one = _mm256_set1_ps(1.0f);
  const __m256 zero = _mm256_setzero_ps();
  for (int r = 0; r < nstore; ++r) {
    const __m256 s = _mm256_set1_ps(rstd[r]);
    const __m256 dl = _mm256_set1_ps(delta[r]);
    const float* xr = x[r];
    float* yr = y[r];
    for (v = 0; v < full; ++v) {
      const __m256 g = gamma ? _mm256_loadu_ps(gamma + v * L) : one;
      const __m256 b = beta ? _mm256_loadu_ps(beta + v * L) : zero;
      const __m256 d = _mm256_sub_ps(_mm256_sub_ps(_mm256_loadu_ps(xr + v * L), m[r]), dl);
      _mm256_storeu_ps(yr + v * L, _mm256_fmadd_ps(_mm256_mul_ps(d, s), g, b));
    }
    if (tail) {
      const __m256 g = gamma ? _mm256_maskload_ps(gamma + full * L, mask) : one;
      const __m256 b = beta ? _mm256_maskload_ps(beta + full * L, mask) : zero;
      const __m256 d =
          _mm256_sub_ps(_mm256_sub_ps(_mm256_maskload_ps(xr + full * L, mask), m[r]), dl);
      _mm256_maskstore_ps(yr + full * L, mask, _mm256_fmadd_ps(_mm256_mul_ps(d, s), g, b));
    }
  }
}

}  // namespace

void layernorm_rows_avx2(std::size_t rows, int c, const float* x, std::ptrdiff_t ldx, float* y,
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
