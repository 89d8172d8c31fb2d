// The kernels of one ISA, in one struct (MLAS's platform struct, XNNPACK's configs): filled
// once per ISA of this build's architecture, chosen by the model's options (nn::active_isa()
// or the ISA a packed weight set was made for). Every op driver takes its kernel from here;
// nothing else picks a kernel by ISA or asks the CPU (nn/cpu_features.h).
//
// The GEMM's micro-kernels have their own list (nn/gemm_kernels.h: NN_GEMM_UKERNELS, one
// entry per tile shape, several per ISA); the table names the first (default) one.
#pragma once

#include <cstddef>
#include <cstdint>

#include "nn/activation_kernel.h"
#include "nn/disparity_row_kernel.h"
#include "nn/dwconv_kernel.h"
#include "nn/gemm_bf16_kernels.h"
#include "nn/gemm_kernels.h"
#include "nn/isa.h"
#include "nn/layernorm_kernel.h"
#include "nn/models/detection/roi_align_kernel.h"
#include "nn/peak_kernel.h"
#include "nn/resize_kernel.h"
#include "nn/winograd_kernel.h"

namespace nn {

struct KernelTable {
  Isa isa;
  int lanes;  // floats per vector register the kernels use (1: scalar)

  // In place: x[i] = act(x[i]); act is static_cast<int>(nn::Act), never None.
  void (*apply_act)(int act, float* x, std::size_t count);
  LayerNormRowsFn layernorm_rows;
  // Null for scalar: nn/dwconv.cpp's reference loop is the scalar kernel (no packing).
  DwConvBlockFn dwconv_block;
  ResizeBilinearRowFn resize_bilinear_row;
  void (*winograd_input_tile)(const WinogradInputTile& t);
  void (*winograd_output_tile)(const WinogradOutputTile& t);
  void (*roi_bin)(const detection::RoiBin& b);
  DisparityRowFn disparity_row;
  // The FMA-peak loop (nn/peak.h): returns the floating-point operations it did.
  double (*peak_fma)(long iterations, float* sink);
  // bfloat16 GEMM (nn/gemm_bf16.h): null where this ISA and CPU have no bf16 products.
  GemmUkernelFn gemm_bf16;
  void (*convert_to_bf16)(int rows, int cols, const float* src, std::ptrdiff_t lds, std::uint16_t* dst,
                          std::ptrdiff_t ldd);
};

// The table of cap_isa(isa): always a supported one.
const KernelTable& kernel_table(Isa isa);

}  // namespace nn
