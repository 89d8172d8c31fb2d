// The bf16 GEMM's micro-kernel and its float -> bf16 conversion, for CPUs with
// AVX512_BF16. A and W arrive as K pairs: one 32-bit element holds (x[k], x[k+1]) in
// bfloat16, low half first, so one VDPBF16PS does two multiply-adds per lane:
// acc += a[k] w[k] + a[k+1] w[k+1], the products exact, the sums in float.
#include <cstdint>
#include <cstring>

#include "nn/gemm_bf16_kernels.h"
#include "nn/arch/x86/gemm_epilogue_avx512.h"

namespace nn {
namespace {

// One tile: R rows of A's K pairs broadcast against NV zmm columns of the pair panel.
struct Tile {
  template <int R, int NV>
  static void run(const GemmTile& t) {
    constexpr int NR = 16 * NV;
    __m512 acc[R][NV];  // all loops unrolled: acc stays in registers (see gemm_avx512.cpp)
    gemm_load_acc<MathOpsAvx512>(acc, t);
    const char* arow[R];
    _Pragma("GCC unroll 16") for (int r = 0; r < R; ++r)
      arow[r] = reinterpret_cast<const char*>(t.a + r * t.lda);
    const float* w = t.w;
    const char* pf = reinterpret_cast<const char*>(t.pf);
    const int pf_lines = t.pf_lines;
    for (int k = 0; k < t.kc; ++k) {  // k counts pairs
      if (k < pf_lines) _mm_prefetch(pf + 64 * k, _MM_HINT_T1);
      __m512bh wv[NV];
      _Pragma("GCC unroll 16") for (int v = 0; v < NV; ++v)
        wv[v] = (__m512bh)_mm512_load_si512(w + 16 * v);
      w += NR;
      _Pragma("GCC unroll 16") for (int r = 0; r < R; ++r) {
        std::int32_t pair;
        std::memcpy(&pair, arow[r] + 4 * k, 4);
        const __m512bh b = (__m512bh)_mm512_set1_epi32(pair);
        _Pragma("GCC unroll 16") for (int v = 0; v < NV; ++v)
          acc[r][v] = _mm512_dpbf16_ps(acc[r][v], b, wv[v]);
      }
    }
    store_tile(acc, t);
  }
};

}  // namespace

void gemm_bf16_8x48_avx512bf16(const GemmTile& tile) {
  gemm_dispatch_rows<Tile, kGemmBf16Mr, kGemmBf16Nr / 16>(tile);
}

void convert_to_bf16_avx512bf16(int rows, int cols, const float* src, std::ptrdiff_t lds,
                                std::uint16_t* dst, std::ptrdiff_t ldd) {
  for (int r = 0; r < rows; ++r) {
    const float* s = src + r * lds;
    std::uint16_t* d = dst + r * ldd;
    int j = 0;
    for (; j + 16 <= cols; j += 16)
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(d + j),
                          (__m256i)_mm512_cvtneps_pbh(_mm512_loadu_ps(s + j)));
    if (j < cols) {
      const __mmask16 m = static_cast<__mmask16>((1u << (cols - j)) - 1u);
      const __m256i v = (__m256i)_mm512_cvtneps_pbh(_mm512_maskz_loadu_ps(m, s + j));
      _mm256_mask_storeu_epi16(d + j, m, v);
    }
    if (cols & 1) d[cols] = 0;  // completes the last K pair
  }
}

}  // namespace nn
