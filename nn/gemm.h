// C = epilogue(A * W^T): the engine's one matrix product, used for 1x1 convolutions,
// Linear layers and (after im2col) general convolutions.
//
// A is row-major [M x K] with row stride lda (NHWC activations: M = pixels, K = channels).
// W is given in PyTorch's layout [N x K] (Linear [out, in]; a 1x1 conv's [out, in, 1, 1])
// and packed once at load into the panel layout of the ISA's micro-kernel.
//
// Epilogue, per output element (m, n), in this order:
//   v = acc + bias[n]                      (bias optional)
//   if (!act_after_residual) v = act(v)
//   v = v * scale[n]                       (scale optional; ConvNeXt's layer scale)
//   v = v + residual[m * ldr + n]          (residual optional; may alias C)
//   if (act_after_residual) v = act(v)     (ResNet: relu(conv + identity))
//   C[m * ldc + n] = v
// The summation order over K is fixed by the packing, not by M, N or the thread
// count, so results are bitwise reproducible across threads.
#pragma once

#include <cstddef>
#include <string>

#include "nn/act.h"
#include "nn/buffer.h"
#include "nn/isa.h"

namespace nn {

struct GemmEpilogue {
  const float* bias = nullptr;
  Act act = Act::None;
  const float* scale = nullptr;
  const float* residual = nullptr;
  std::ptrdiff_t ldr = 0;
  bool act_after_residual = false;
};

// W packed for one ISA's micro-kernel family.
class GemmWeights {
 public:
  GemmWeights() = default;
  // w: [n x k] row-major. Packs for `isa` (default: the active ISA), for the kernel
  // gemm_kernel_name(isa, n) names (the ISA's default unless that pads N badly).
  static GemmWeights pack(const float* w, int n, int k, Isa isa = active_isa());
  // Packs for one micro-kernel of the list in nn/gemm_kernels.h; tests and benchmarks
  // use it to cover and compare every kernel.
  static GemmWeights pack_for_ukernel(const float* w, int n, int k, int ukernel);
  int n() const { return n_; }
  int k() const { return k_; }
  Isa isa() const { return isa_; }
  int ukernel() const { return ukernel_; }
  const float* panels() const { return data_.data(); }
  std::size_t bytes() const { return data_.size() * sizeof(float); }

 private:
  AlignedBuffer data_;
  int n_ = 0, k_ = 0;
  Isa isa_ = Isa::Scalar;
  int ukernel_ = -1;
};

// Single-threaded: computes all M rows. Safe to call from inside a parallel region.
void gemm(int m, const float* a, std::ptrdiff_t lda, const GemmWeights& w, float* c,
          std::ptrdiff_t ldc, const GemmEpilogue& ep = {});

// Splits the rows (and, for small M, the columns) over the team's threads; bitwise
// identical to gemm(). Call from outside a parallel region.
void gemm_parallel(int m, const float* a, std::ptrdiff_t lda, const GemmWeights& w, float* c,
                   std::ptrdiff_t ldc, const GemmEpilogue& ep = {});

// Plain scalar reference on unpacked W ([n x k]): double accumulation rounded once to
// float, then the float epilogue with act_ref(). The kernels are tested against it.
void gemm_ref(int m, int n, int k, const float* a, std::ptrdiff_t lda, const float* w, float* c,
              std::ptrdiff_t ldc, const GemmEpilogue& ep = {});

// Name of the micro-kernel pack() picks for `isa` and an N-column matrix, e.g.
// "gemm_f32_8x48_avx512".
const char* gemm_kernel_name(Isa isa, int n);

}  // namespace nn
