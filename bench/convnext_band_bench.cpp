// One thread's share of a ConvNeXt-Tiny block at a 1280x1920 input, run as the model's
// banded path runs it (nn/models/convnext.cpp, run_block_banded / run_mlp_rows): per band
// of 8 image rows the depthwise 7x7 (dwconv_rows) into a band buffer, then 64-row tiles of
// LayerNorm -> pw1 + GELU -> pw2 + layer scale + residual. Two placements of the
// residual and the block output:
//   res_tile:0  in tensors of the share's full size, as in the model (stage 1: 29 MB each,
//               larger than the L3 share of one thread)
//   res_tile:1  in two 64-row tiles (read, written) that stay in cache
// The difference is what the residual read and the output write cost the block; set
// against gemm_tile64 (nn_bench, A and C in cache) it says where a stage's MLP rate goes.
// The weights are seeded (the LayerNorm affine is folded into pw1 in the model, so the
// LayerNorm here has none either). FLOPs: the depthwise and both 1x1 layers.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <vector>

#include "bench/peak.h"
#include "bench/random_data.h"
#include "nn/buffer.h"
#include "nn/dwconv.h"
#include "nn/gemm.h"
#include "nn/isa.h"
#include "nn/layernorm.h"
#include "nn/tensor.h"
#include "nn/threads.h"

namespace {

constexpr int kBand = 8;   // image rows per band (kDwMlpBand in the model)
constexpr int kTile = 64;  // rows per MLP tile (kMlpTile)

void BM_ConvNeXtBand(benchmark::State& state) {
  const int h = static_cast<int>(state.range(0)), w = static_cast<int>(state.range(1));
  const int c = static_cast<int>(state.range(2));
  const bool res_in_tile = state.range(3) != 0;
  const auto isa = static_cast<nn::Isa>(state.range(4));
  if (!nn::isa_supported(isa)) {
    state.SkipWithError("ISA not supported by this CPU");
    return;
  }
  nn::set_isa(isa);
  nn::set_num_threads(1);
  nnbench::UniformStream u;
  nn::DwConvParams dp;
  dp.kh = dp.kw = 7;
  dp.pad_h = dp.pad_w = 3;
  const std::vector<float> dw_w = u.vector(static_cast<std::size_t>(c) * 49, 0.2f), dw_b = u.vector(c, 1.0f);
  const nn::DwConvWeights dw = nn::DwConvWeights::pack(dw_w.data(), dw_b.data(), c, dp);
  const std::vector<float> w1 = u.vector(4 * static_cast<std::size_t>(c) * c, 0.1f), b1 = u.vector(4 * c, 1.0f);
  const std::vector<float> w2 = u.vector(4 * static_cast<std::size_t>(c) * c, 0.1f), b2 = u.vector(c, 1.0f);
  const std::vector<float> scale = u.vector(c, 1.0f);
  const nn::GemmWeights pw1 = nn::GemmWeights::pack(w1.data(), 4 * c, c);
  const nn::GemmWeights pw2 = nn::GemmWeights::pack(w2.data(), c, 4 * c);

  const nn::Shape shape{1, h, w, c};
  const std::size_t m = static_cast<std::size_t>(h) * w;
  const std::vector<float> x = u.vector(m * c, 1.0f);
  nn::AlignedBuffer out(m * c), band(static_cast<std::size_t>(kBand) * w * c);
  nn::AlignedBuffer ln(static_cast<std::size_t>(kTile) * c), hid(static_cast<std::size_t>(kTile) * 4 * c);
  nn::AlignedBuffer tile_res(static_cast<std::size_t>(kTile) * c), tile_out(static_cast<std::size_t>(kTile) * c);
  std::copy(x.begin(), x.begin() + kTile * c, tile_res.data());
  const nn::ConstTensorView in(x.data(), shape);

  nn::GemmEpilogue e1;
  e1.bias = b1.data();
  e1.act = nn::Act::Gelu;
  nn::GemmEpilogue e2;
  e2.bias = b2.data();
  e2.scale = scale.data();
  e2.ldr = c;
  for (auto _ : state) {
    for (int y0 = 0; y0 < h; y0 += kBand) {
      const int y1 = std::min(h, y0 + kBand);
      nn::dwconv_rows(in, dw, 0, y0, y1, band.data());
      const std::size_t pixels = static_cast<std::size_t>(y1 - y0) * w;
      for (std::size_t p = 0; p < pixels; p += kTile) {
        const int rows = static_cast<int>(std::min<std::size_t>(kTile, pixels - p));
        const std::size_t off = (static_cast<std::size_t>(y0) * w + p) * c;
        nn::layernorm(rows, c, band.data() + p * c, c, ln.data(), c, nullptr, nullptr, 1e-6f);
        nn::gemm(rows, ln.data(), c, pw1, hid.data(), 4 * c, e1);
        e2.residual = res_in_tile ? tile_res.data() : x.data() + off;
        nn::gemm(rows, hid.data(), 4 * c, pw2, res_in_tile ? tile_out.data() : out.data() + off, c, e2);
      }
    }
    benchmark::ClobberMemory();
  }
  const double flops = 2.0 * static_cast<double>(m) * c * (49 + 8 * c);
  nnbench::set_flop_counters(state, flops, 1);
  state.SetLabel(nn::isa_name(isa));
  nn::set_num_threads(0);
  nn::set_isa(nn::detect_isa());
}

// One thread's half of stages 1, 2 and 3 at 1280x1920 (2 threads), the residual in the
// block's tensors or in a cached tile, AVX2 (isa:1) and AVX-512 (isa:2).
void band_shapes(benchmark::internal::Benchmark* b) {
  const int stages[][3] = {{160, 480, 96}, {80, 240, 192}, {40, 120, 384}};
  for (const auto& s : stages)
    for (int isa : {1, 2})
      for (int res_tile : {0, 1}) b->Args({s[0], s[1], s[2], res_tile, isa});
}

BENCHMARK(BM_ConvNeXtBand)
    ->ArgNames({"h", "w", "c", "res_tile", "isa"})
    ->Apply(band_shapes)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(1.0);

}  // namespace
