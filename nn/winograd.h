// Winograd F(4x4, 3x3) convolution for the 3x3, stride-1, pad-1 layers of NHWC models
// (ResNet bottlenecks, FPN outputs, the RPN head). Each 4x4 output tile costs 36
// products over C_in instead of 144, so these layers need a quarter of the multiply-adds
// of the direct (im2col) form. The 36 products of a block of tiles are 36 GEMMs
// [tiles x C_in] x [C_in x C_out] on the engine's packed kernels (nn/gemm.h); the input
// and output transforms are nn/winograd_transform.h.
//
// Accuracy: the transforms' constants (up to 8 in A^T, 1/24 in G) make rounding errors
// larger than the direct sum's: on random data about 1e-5 of the output range for a
// single layer against 6e-7 direct; through the 18 such layers of ResNet-50-FPN the
// features stay within about 2e-6 of torchvision's range. nn::set_winograd(false), or
// NN_WINOGRAD=0 in the environment, packs these layers for the direct path instead.
#pragma once

#include <cstddef>
#include <vector>

#include "nn/act.h"
#include "nn/gemm.h"
#include "nn/tensor.h"

namespace nn {

// Whether weights packed from now on use Winograd where it applies (default: yes,
// unless NN_WINOGRAD=0). Not thread-safe against concurrent packing.
bool winograd_enabled();
void set_winograd(bool on);

// Layers with at least this many input and output channels use it: below, the
// transforms cost more than the products they save.
constexpr int kWinogradMinChannels = 16;

class WinogradWeights {
 public:
  WinogradWeights() = default;
  // w: PyTorch [cout, cin, 3, 3]. The 36 transformed matrices G g G^T, computed in
  // double and rounded once, each packed for `isa`'s GEMM kernel.
  static WinogradWeights pack(const float* w, int cin, int cout, Isa isa = active_isa());
  bool empty() const { return u_.empty(); }
  int cin() const { return cin_; }
  int cout() const { return cout_; }
  Isa isa() const { return isa_; }
  const GemmWeights& product(int xi) const { return u_[xi]; }
  std::size_t bytes() const;

 private:
  std::vector<GemmWeights> u_;  // 36 x [cout x cin]
  int cin_ = 0, cout_ = 0;
  Isa isa_ = Isa::Scalar;
};

// Tiles per block (the GEMMs' M) and the floats of scratch one thread needs.
int winograd_block_tiles(int cin, int cout);
std::size_t winograd_scratch_floats(int cin, int cout);

// out = epilogue(conv3x3(in)), stride 1, pad 1; the epilogue as nn/gemm.h's (bias, act,
// residual, act_after_residual; no scale). Tiles are split over the team's threads; each
// output element's arithmetic does not depend on the split. scratch: num_threads() x
// winograd_scratch_floats(cin, cout) floats, 64-byte aligned.
void winograd_conv2d(const ConstTensorView& in, const WinogradWeights& w, const float* bias,
                     const TensorView& out, float* scratch, Act act = Act::None,
                     const float* residual = nullptr, bool act_after_residual = false);

}  // namespace nn
