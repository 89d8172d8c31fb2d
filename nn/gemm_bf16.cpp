// The bf16 GEMM around its AVX512_BF16 micro-kernel: packing into K-pair panels, the
// conversion and the calls into gemm.cpp's blocking and threading driver
// (the pair arrays are 4-byte elements to it, so the blocking, prefetching, row/column
// split and bitwise determinism are the float GEMM's own).
#include "nn/gemm_bf16.h"

#include <cstdint>
#include <cstring>
#include <string>

#include "nn/error.h"
#include "nn/gemm_bf16_kernels.h"
#include "nn/isa.h"
#include "nn/kernel_table.h"

namespace nn {

namespace {
// The hardware's bf16 kernels (the best ISA's table): the packed layout is theirs, so the
// same kernel runs whatever cap a later call has (this may run on a worker thread).
const KernelTable& bf16_kernels() { return kernel_table(detect_isa()); }
}  // namespace

bool bf16_gemm_available() { return bf16_kernels().gemm_bf16 && active_isa() == detect_isa(); }

bf16 f32_to_bf16(float x) {
  std::uint32_t u;
  std::memcpy(&u, &x, 4);
  if ((u & 0x7FFFFFFFu) > 0x7F800000u) return static_cast<bf16>((u >> 16) | 0x0040u);  // quiet NaN
  // VCVTNEPS2BF16 treats denormal inputs as zero (keeping the sign); the reference too.
  if ((u & 0x7F800000u) == 0) return static_cast<bf16>((u >> 16) & 0x8000u);
  u += 0x7FFFu + ((u >> 16) & 1u);  // round to nearest, ties to even; overflows to inf
  return static_cast<bf16>(u >> 16);
}

float bf16_to_f32(bf16 x) {
  const std::uint32_t u = static_cast<std::uint32_t>(x) << 16;
  float f;
  std::memcpy(&f, &u, 4);
  return f;
}

void convert_to_bf16(int rows, int cols, const float* src, std::ptrdiff_t lds, bf16* dst,
                     std::ptrdiff_t ldd) {
  if (rows <= 0 || cols <= 0) return;
  // Both forms give the same bits.
  if (bf16_kernels().convert_to_bf16) return bf16_kernels().convert_to_bf16(rows, cols, src, lds, dst, ldd);
  for (int r = 0; r < rows; ++r) {
    for (int j = 0; j < cols; ++j) dst[r * ldd + j] = f32_to_bf16(src[r * lds + j]);
    if (cols & 1) dst[r * ldd + cols] = 0;
  }
}

GemmWeightsBf16 GemmWeightsBf16::pack(const float* w, int n, int k) {
  if (!bf16_gemm_available())
    throw Error("gemm_bf16: this CPU has no AVX512_BF16 (or the kernels are capped below avx512)");
  if (n <= 0 || k <= 0)
    throw Error("gemm_bf16: cannot pack a weight matrix of shape [" + std::to_string(n) + " x " +
                std::to_string(k) + "]");
  if (!w) throw Error("gemm_bf16: weight pointer is null");
  constexpr int nr = kGemmBf16Nr;
  const std::size_t panels = static_cast<std::size_t>((n + nr - 1) / nr);
  const std::size_t pairs = static_cast<std::size_t>((k + 1) / 2);
  GemmWeightsBf16 out;
  out.data_.resize(panels * pairs * nr);  // one pair per 4-byte slot; zero-filled padding
  bf16* dst = reinterpret_cast<bf16*>(out.data_.data());
  for (std::size_t p = 0; p < panels; ++p)
    for (std::size_t q = 0; q < pairs; ++q)
      for (int j = 0; j < nr; ++j) {
        const std::size_t col = p * nr + j;
        if (col >= static_cast<std::size_t>(n)) continue;
        const float* row = w + col * static_cast<std::size_t>(k);
        bf16* lane = dst + ((p * pairs + q) * nr + j) * 2;
        lane[0] = f32_to_bf16(row[2 * q]);
        if (2 * q + 1 < static_cast<std::size_t>(k)) lane[1] = f32_to_bf16(row[2 * q + 1]);
      }
  out.n_ = n;
  out.k_ = k;
  return out;
}

namespace {

// The pair view of a call, for gemm.cpp's driver; checks the arguments first.
GemmPacked pair_view(int m, const bf16* a, std::ptrdiff_t lda, const GemmWeightsBf16& w,
                     const float* c, std::ptrdiff_t ldc, const GemmEpilogue& ep) {
  if (w.empty()) throw Error("gemm_bf16: weights were not packed");
  if (!bf16_gemm_available())
    throw Error("gemm_bf16: this CPU has no AVX512_BF16 (or the kernels are capped below avx512)");
  if (m < 0) throw Error("gemm_bf16: negative row count " + std::to_string(m));
  if (m > 0 && (!a || !c)) throw Error("gemm_bf16: null A or C");
  const int kp = (w.k() + 1) / 2;
  if (lda % 2 != 0 || lda < 2 * kp)
    throw Error("gemm_bf16: lda " + std::to_string(lda) + " must be even and >= " +
                std::to_string(2 * kp));
  if (ldc < w.n())
    throw Error("gemm_bf16: ldc " + std::to_string(ldc) + " < N " + std::to_string(w.n()));
  if (ep.residual && ep.ldr < w.n())
    throw Error("gemm_bf16: ldr " + std::to_string(ep.ldr) + " < N " + std::to_string(w.n()));
  return {reinterpret_cast<const float*>(w.panels()), w.n(), kp, kGemmBf16Mr, kGemmBf16Nr,
          bf16_kernels().gemm_bf16};
}

const float* pairs_of(const bf16* a) { return reinterpret_cast<const float*>(a); }

}  // namespace

void gemm_bf16(int m, const bf16* a, std::ptrdiff_t lda, const GemmWeightsBf16& w, float* c,
               std::ptrdiff_t ldc, const GemmEpilogue& ep) {
  const GemmPacked p = pair_view(m, a, lda, w, c, ldc, ep);
  if (m == 0) return;
  gemm_blocked(0, m, 0, (p.n + p.nr - 1) / p.nr, pairs_of(a), lda / 2, p, c, ldc, ep);
}

void gemm_bf16_parallel(int m, const bf16* a, std::ptrdiff_t lda, const GemmWeightsBf16& w,
                        float* c, std::ptrdiff_t ldc, const GemmEpilogue& ep) {
  const GemmPacked p = pair_view(m, a, lda, w, c, ldc, ep);
  if (m == 0) return;
  gemm_split(m, pairs_of(a), lda / 2, p, c, ldc, ep);
}

const char* gemm_bf16_kernel_name() { return "gemm_bf16_8x48_avx512bf16"; }

}  // namespace nn
