// AVX2 inner loop of bilinear resizing: 8 channels at a time, with the same three
// fused multiply-adds per element as the scalar path (so both give the same bits).
#include <immintrin.h>

#include "nn/resize_kernel.h"

namespace nn {

void resize_bilinear_row_avx2(const float* row0, const float* row1, float h0, float h1,
                              const long long* x0, const long long* x1, const float* w0,
                              const float* w1, int count, int c, float* out) {
  const __m256 vh0 = _mm256_set1_ps(h0), vh1 = _mm256_set1_ps(h1);
  const int tail = c % 8;
  const __m256i mask =
      _mm256_cmpgt_epi32(_mm256_set1_epi32(tail), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
  for (int i = 0; i < count; ++i, out += c) {
    const float *a = row0 + x0[i], *b = row0 + x1[i], *p = row1 + x0[i], *q = row1 + x1[i];
    const __m256 vw0 = _mm256_set1_ps(w0[i]), vw1 = _mm256_set1_ps(w1[i]);
    int ch = 0;
    for (; ch + 8 <= c; ch += 8) {
      const __m256 t0 = _mm256_fmadd_ps(_mm256_loadu_ps(a + ch), vw0,
                                        _mm256_mul_ps(_mm256_loadu_ps(b + ch), vw1));
      const __m256 t1 = _mm256_fmadd_ps(_mm256_loadu_ps(p + ch), vw0,
                                        _mm256_mul_ps(_mm256_loadu_ps(q + ch), vw1));
      _mm256_storeu_ps(out + ch, _mm256_fmadd_ps(t0, vh0, _mm256_mul_ps(t1, vh1)));
    }
    if (tail) {
      const __m256 t0 = _mm256_fmadd_ps(_mm256_maskload_ps(a + ch, mask), vw0,
                                        _mm256_mul_ps(_mm256_maskload_ps(b + ch, mask), vw1));
      const __m256 t1 = _mm256_fmadd_ps(_mm256_maskload_ps(p + ch, mask), vw0,
                                        _mm256_mul_ps(_mm256_maskload_ps(q + ch, mask), vw1));
      _mm256_maskstore_ps(out + ch, mask, _mm256_fmadd_ps(t0, vh0, _mm256_mul_ps(t1, vh1)));
    }
  }
}

}  // namespace nn
