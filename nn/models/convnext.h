// torchvision ConvNeXt `features` (stem, stages of CNBlocks, downsampling layers),
// generic over the configuration: stage widths and block counts are read from the
// weights, so ConvNeXt-T/S/B and small test configurations all run.
//
// Exactly torchvision 0.14's eval-mode computation:
//   stem:  Conv2d(3, C0, 4, stride 4) -> LayerNorm2d(C0, eps 1e-6)
//   block: x + layer_scale * Linear2(GELU(Linear1(LayerNorm(dwconv7x7(x)))))
//   down:  LayerNorm2d(Ci) -> Conv2d(Ci, Ci+1, 2, stride 2)
// NHWC inside; PyTorch's NCHW at the input.
#pragma once

#include <string>
#include <vector>

#include "nn/buffer.h"
#include "nn/conv2d.h"
#include "nn/dump.h"
#include "nn/dwconv.h"
#include "nn/gemm.h"
#include "nn/gemm_bf16.h"
#include "nn/precision.h"
#include "nn/profiler.h"
#include "nn/tensor.h"
#include "weights/safetensors.h"
#include "weights/tensor_spec.h"

namespace nn {

struct ConvNeXtConfig {
  std::vector<int> dims;    // channels per stage
  std::vector<int> depths;  // blocks per stage
  float eps = 1e-6f;
  std::string describe() const;  // "dims [96, 192, 384, 768], depths [3, 3, 9, 3]"
  bool operator==(const ConvNeXtConfig& o) const { return dims == o.dims && depths == o.depths; }
};

ConvNeXtConfig convnext_tiny_config();
ConvNeXtConfig convnext_small_config();
ConvNeXtConfig convnext_base_config();

// Reads the configuration from tensor names and shapes under `prefix` ("features.").
// Throws weights::Error naming the file if the stem or the first block is missing.
ConvNeXtConfig convnext_config_from(const weights::SafeTensors& st, const std::string& prefix);

// Every tensor the model reads, with its shape (torchvision state_dict names).
std::vector<weights::TensorSpec> convnext_tensor_specs(const ConvNeXtConfig& cfg,
                                                       const std::string& prefix);

class ConvNeXt {
 public:
  // Checks every expected tensor (first problem reported by name) and repacks the
  // weights for the active ISA. The SafeTensors object may be freed afterwards.
  // Precision::Bf16 runs the MLP GEMMs (90 % of the work) in bfloat16; it throws
  // nn::Error when the CPU (or the kernel cap) has no AVX512_BF16.
  ConvNeXt(const weights::SafeTensors& st, const std::string& prefix = "features.",
           Precision precision = Precision::F32);

  const ConvNeXtConfig& config() const { return cfg_; }
  int out_channels() const { return cfg_.dims.back(); }
  Precision precision() const { return precision_; }

  // Plans the activation arena for NCHW inputs [n, 3, h, w] and the current thread
  // count. Throws nn::Error for h or w below 32 or n below 1.
  void plan(int n, int h, int w);
  Shape input_shape() const { return in_shape_; }  // NHWC view of the planned input
  Shape output_shape() const { return out_shape_; }  // NHWC
  std::size_t arena_bytes() const;
  std::size_t weight_bytes() const { return weight_bytes_; }

  // Runs the planned input (NCHW, n*3*h*w floats). Returns an NHWC view into the
  // arena, valid until the next forward or plan. Allocates nothing.
  ConstTensorView forward(const float* input_nchw);

  Profiler& profiler() { return prof_; }
  double flops() const;  // multiply-adds x 2 of one forward at the planned size

  // Intermediate tensors of the next forwards go to `sink` (null: off, the default).
  // Names are torchvision's `features.*` module names (nn/dump.h); the stem, every
  // downsampling layer, every block's depthwise output `features.S.B.block.0` and
  // block output `features.S.B`, every stage `features.S` and `features`.
  // With a sink, each block's MLP also runs layer by layer up to its GELU for the dump
  // (block.1 .. block.4, channels-last [N, H, W, C] as in PyTorch; f32 only): the
  // dump.path text below says so.
  void set_dump(DumpSink* sink) { dump_ = sink; }
  DumpSink* dump() const { return dump_; }
  std::string dump_path() const { return dump_path_of(precision_); }
  static std::string dump_path_of(Precision precision);

 private:
  // LayerNorm's gamma/beta are folded into pw1 and the layer scale into pw2 at load
  // (in double): the MLP normalises without an affine step and pw2's epilogue is
  // bias + residual. The downsampling LayerNorm's gamma/beta go into the 2x2 conv.
  struct Block {
    DwConvWeights dw;
    AlignedBuffer b1, b2;
    GemmWeights pw1, pw2;          // Precision::F32
    GemmWeightsBf16 pw1_bf16, pw2_bf16;  // Precision::Bf16 (the other pair stays empty)
    int prof_dw = -1, prof_mlp = -1;
    // PyTorch names: "features.S.B", its depthwise conv, and what the fused MLP covers.
    std::string name, dw_name, covers;
    // Dumps only: the MLP's first layers as PyTorch runs them (block.1 .. block.4) and
    // the LayerNorm's own affine (the fused path has it folded into pw1).
    std::string perm_name, ln_name, pw1_name, gelu_name;
    AlignedBuffer ln_gamma, ln_beta;
  };
  struct Stage {
    int dim = 0;
    bool has_down = false;  // downsampling layer before this stage (all but the first)
    Conv2dWeights down;     // LayerNorm gamma/beta folded in
    std::vector<Block> blocks;
    int prof_down = -1;
    std::string name, down_name, down_covers;  // "features.2s+1", "features.2s"
    int down_chunk = 1;       // output rows per LayerNorm + im2col + GEMM step
    bool down_whole = false;  // small: one im2col, then a GEMM split over columns
    std::size_t mlp_tile = 0; // rows per fused MLP tile, 0: layer by layer (fused_mlp_rows)
    int band = 0;             // image rows per depthwise -> MLP band, 0: whole-map depthwise
  };

  void run_stem(const float* input_nchw, Shape s);
  void run_down(const Stage& st, Shape prev, Shape s);
  // upward: the order of a banded block's bands (run_block_banded); the result is the same.
  void run_block(const Stage& st, const Block& b, Shape s, bool upward);
  void run_block_banded(const Stage& st, const Block& b, Shape s, bool upward);
  void dump_mlp_layers(const Block& b, Shape s);
  // Scratch of one MLP tile (or of all rows on the unfused path): the normalised rows,
  // the hidden rows and, for bf16, both again in bfloat16.
  struct MlpScratch {
    float* ln;
    float* hid;
    bf16* ln_bf16;
    bf16* hid_bf16;
  };
  std::size_t mlp_scratch_floats(std::size_t rows, int c) const;
  MlpScratch mlp_scratch(float* base, std::size_t rows, int c) const;
  // The fused MLP on `rows` rows: t the depthwise output, res the residual, y the result
  // (may be res).
  void run_mlp_rows(const Block& b, int c, int rows, const float* t, const float* res, float* y,
                    const MlpScratch& s);

  ConvNeXtConfig cfg_;
  Precision precision_ = Precision::F32;
  // The stem's GEMM reads patches straight from the NCHW input, so its K order is
  // PyTorch's (c, ky, kx) and W packs without reordering.
  GemmWeights stem_w_;
  AlignedBuffer stem_b_, stem_gamma_, stem_beta_;
  int stem_chunk_ = 1;  // output rows per im2col + GEMM + LayerNorm step
  std::vector<Stage> stages_;
  std::size_t weight_bytes_ = 0;

  // Arena: two ping-pong activation buffers and per-thread scratch.
  Shape in_shape_, out_shape_;
  std::vector<Shape> stage_shapes_;
  AlignedBuffer act_a_, act_b_, scratch_;
  std::size_t scratch_per_thread_ = 0, conv_scratch_ = 0;
  int planned_threads_ = 0;
  std::vector<double> band_dw_ms_;  // per thread: depthwise time of a banded block (profiling)
  Profiler prof_;
  int prof_stem_ = -1;
  DumpSink* dump_ = nullptr;
  std::string stem_name_, stem_covers_, name_;  // "features.0", its parts, "features"
};

}  // namespace nn
