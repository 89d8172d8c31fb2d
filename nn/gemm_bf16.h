// The optional bfloat16 matrix product (never the default): C = epilogue(A * W^T) with A and
// W rounded to bfloat16 (round to nearest even) and the products summed in float by
// AVX512_BF16's VDPBF16PS, which multiplies two K steps per instruction and so doubles the
// multiply-add rate of the float GEMM. ConvNeXt's `--precision bf16` uses it for the MLP
// GEMMs; the accuracy cost against the float path is reported, not hidden
// (docs/PERFORMANCE.md).
//
// Same conventions as nn/gemm.h: W in PyTorch's [N x K] layout, packed once at load (here
// into K-pair panels: panel p holds w[k][p*NR + j] and w[k+1][p*NR + j] side by side in one
// 32-bit lane); the same GemmEpilogue, applied in float; the summation order over K fixed
// by the packing, so results are bitwise identical for any row split or thread count.
// A is bf16, row-major, with K padded to an even count (convert_to_bf16 writes the pad).
// The reference is gemm_ref (nn/gemm.h) on the operands widened back to float: bfloat16
// widens exactly and float products are exact in double, so it is the exact sum, rounded
// once (tests/nn/test_gemm.cpp runs every kernel test on this GEMM that way).
#pragma once

#include <cstddef>
#include <cstdint>

#include "nn/buffer.h"
#include "nn/gemm.h"

namespace nn {

using bf16 = std::uint16_t;

// True when the CPU has AVX512_BF16 on top of nn/isa.h's AVX-512 set and the active ISA
// (the ExecOptions cap, nn/exec.h) is AVX-512; callers fail with a clear error otherwise.
bool bf16_gemm_available();

// Round to nearest even; NaN stays NaN (quiet), infinities stay infinite. The reference
// conversion: convert_to_bf16 gives the same bits.
bf16 f32_to_bf16(float x);
float bf16_to_f32(bf16 x);

// rows x cols floats (row stride lds) to bf16 rows of stride ldd >= cols + (cols & 1); an
// odd cols gets one zero pad element per row so every K pair is complete.
void convert_to_bf16(int rows, int cols, const float* src, std::ptrdiff_t lds, bf16* dst,
                     std::ptrdiff_t ldd);

class GemmWeightsBf16 {
 public:
  GemmWeightsBf16() = default;
  // w: [n x k] row-major floats, rounded to bf16 and packed. Throws nn::Error when
  // !bf16_gemm_available() or for an empty shape.
  static GemmWeightsBf16 pack(const float* w, int n, int k);
  int n() const { return n_; }
  int k() const { return k_; }
  const bf16* panels() const { return reinterpret_cast<const bf16*>(data_.data()); }
  std::size_t bytes() const { return data_.size() * sizeof(float); }
  bool empty() const { return data_.size() == 0; }

 private:
  AlignedBuffer data_;  // bf16 pairs, one per float-sized slot
  int n_ = 0, k_ = 0;
};

// Single-threaded, all M rows; safe inside a parallel region. lda in elements, even.
void gemm_bf16(int m, const bf16* a, std::ptrdiff_t lda, const GemmWeightsBf16& w, float* c,
               std::ptrdiff_t ldc, const GemmEpilogue& ep = {});

// Splits rows (or, for small M, columns) over the team's threads; bitwise equal to gemm_bf16.
void gemm_bf16_parallel(int m, const bf16* a, std::ptrdiff_t lda, const GemmWeightsBf16& w,
                        float* c, std::ptrdiff_t ldc, const GemmEpilogue& ep = {});

// "gemm_bf16_8x48_avx512bf16" or the like: tile and ISA.
const char* gemm_bf16_kernel_name();

}  // namespace nn
