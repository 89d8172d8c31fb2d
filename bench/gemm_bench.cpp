// Every distinct GEMM of ConvNeXt-Tiny at a 1280x1920 input, with its real epilogue, for
// every micro-kernel of nn/gemm_kernels.h this CPU runs:
//   gemm/<shape>/<kernel>/threads:T   gemm_parallel over all M rows (A, C in DRAM)
//   gemm_tile64/<shape>/<kernel>/threads:T   gemm() on 64-row tiles whose A and C stay in
//     cache, as the model's fused LN -> pw1 -> GELU -> pw2 loop calls it (T threads each
//     run their own tiles)
// pct_peak is relative to the FMA peak of the kernel's own ISA (bench/peak.h). With
// AVX512_BF16 the tile benchmark also runs the bf16 GEMM (kernel gemm_bf16_8x48_avx512bf16,
// A already in bf16 as the model's tiles hand it over); its pct_peak is against the FP32
// peak, so up to 200 %.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdlib>
#include <string>
#include <vector>

#include "bench/peak.h"
#include "nn/buffer.h"
#include "nn/gemm.h"
#include "nn/gemm_bf16.h"
#include "nn/gemm_kernels.h"
#include "nn/exec.h"
#include "nn/threads.h"

namespace {

enum class Epi { Bias, BiasGelu, BiasScaleResidual };

struct GemmShape {
  const char* name;
  int m, k, n;
  Epi epi;
};

// M = output pixels; stem 4x4/4 conv and 2x2/2 downsampling convs as im2col GEMMs.
const GemmShape kShapes[] = {
    {"stem_k48_n96", 153600, 48, 96, Epi::Bias},
    {"s1_pw1_k96_n384", 153600, 96, 384, Epi::BiasGelu},
    {"s1_pw2_k384_n96", 153600, 384, 96, Epi::BiasScaleResidual},
    // s1_pw1 without its GELU: the difference is what the GELU epilogue costs at K = 96,
    // where it weighs most (96 FMAs per output vector against its 9 FMA-pipe slots).
    {"s1_pw1_nogelu_k96_n384", 153600, 96, 384, Epi::Bias},
    {"ds1_k384_n192", 38400, 384, 192, Epi::Bias},
    {"s2_pw1_k192_n768", 38400, 192, 768, Epi::BiasGelu},
    {"s2_pw2_k768_n192", 38400, 768, 192, Epi::BiasScaleResidual},
    {"ds2_k768_n384", 9600, 768, 384, Epi::Bias},
    {"s3_pw1_k384_n1536", 9600, 384, 1536, Epi::BiasGelu},
    {"s3_pw2_k1536_n384", 9600, 1536, 384, Epi::BiasScaleResidual},
    {"ds3_k1536_n768", 2400, 1536, 768, Epi::Bias},
    {"s4_pw1_k768_n3072", 2400, 768, 3072, Epi::BiasGelu},
    {"s4_pw2_k3072_n768", 2400, 3072, 768, Epi::BiasScaleResidual},
    // Faster R-CNN at 720x1280 (768x1344 padded): ResNet-50 1x1 convs, a 3x3 conv as
    // im2col, the RoI box head's fc6 (1000 RoIs).
    {"r50_l1_k64_n256", 64512, 64, 256, Epi::Bias},
    {"r50_l1_k256_n64", 64512, 256, 64, Epi::Bias},
    {"r50_l3_k1024_n256", 4032, 1024, 256, Epi::Bias},
    {"fpn3x3_k2304_n256", 16128, 2304, 256, Epi::Bias},
    {"fc6_k12544_n1024", 1000, 12544, 1024, Epi::Bias},
    // MobileNetV3-Large at 720x1280: the stem as im2col, narrow 1x1 convs.
    {"mnv3_stem_k27_n16", 258048, 27, 16, Epi::Bias},
    {"mnv3_b1_k16_n16", 258048, 16, 16, Epi::Bias},
    {"mnv3_b2_k16_n64", 258048, 16, 64, Epi::Bias},
    {"mnv3_b3_k72_n24", 64512, 72, 24, Epi::Bias},
    {"mnv3_b4_k72_n40", 16128, 72, 40, Epi::Bias},
    {"mnv3_b11_k480_n112", 4032, 480, 112, Epi::Bias},
    {"mnv3_b13_k672_n160", 1008, 672, 160, Epi::Bias},
};

constexpr int kTileRows = 64;
constexpr int kTilesPerIteration = 16;

// Deterministic, finite, not-denormal values in [-1, 1).
void fill(float* p, std::size_t n, unsigned salt) {
  unsigned s = 2463534242u ^ salt;
  for (std::size_t i = 0; i < n; ++i) {
    s ^= s << 13;
    s ^= s >> 17;
    s ^= s << 5;
    p[i] = static_cast<float>(s >> 8) * (2.0f / 16777216.0f) - 1.0f;
  }
}

constexpr int kBf16 = -1;  // "ukernel" of the bf16 GEMM

struct Problem {
  nn::GemmWeights w;
  nn::GemmWeightsBf16 wb;
  nn::AlignedBuffer bias, scale;
  Problem(const GemmShape& s, int ukernel) : bias(s.n), scale(s.n) {
    nn::AlignedBuffer wt(static_cast<std::size_t>(s.n) * s.k);
    fill(wt.data(), wt.size(), 1);
    // ~unit-variance sums, so GELU sees its whole interesting range.
    for (std::size_t i = 0; i < wt.size(); ++i) wt[i] *= 1.7f / std::sqrt(static_cast<float>(s.k));
    if (ukernel == kBf16)
      wb = nn::GemmWeightsBf16::pack(wt.data(), s.n, s.k);
    else
      w = nn::GemmWeights::pack_for_ukernel(wt.data(), s.n, s.k, ukernel);
    fill(bias.data(), bias.size(), 2);
    fill(scale.data(), scale.size(), 3);
    for (std::size_t i = 0; i < scale.size(); ++i) scale[i] *= 1e-3f;  // layer scale ~ 1e-6..1
  }
  nn::GemmEpilogue epilogue(const GemmShape& s, float* c, std::ptrdiff_t ldc) const {
    nn::GemmEpilogue ep;
    ep.bias = bias.data();
    if (s.epi == Epi::BiasGelu) ep.act = nn::Act::Gelu;
    if (s.epi == Epi::BiasScaleResidual) {
      ep.scale = scale.data();
      ep.residual = c;  // the block's input, updated in place as in the model
      ep.ldr = ldc;
    }
    return ep;
  }
};

// pct_peak refers to the kernel's ISA: the peak loop follows the active ISA.
class IsaOverride {
 public:
  explicit IsaOverride(nn::Isa isa) : saved_(nn::active_isa()) { nn::set_isa(isa); }
  ~IsaOverride() { nn::set_isa(saved_); }
 private:
  nn::Isa saved_;
};

void bm_full(benchmark::State& state, GemmShape s, int ukernel, int threads) {
  IsaOverride isa(nn::gemm_ukernel(ukernel).isa);
  const Problem p(s, ukernel);
  nn::AlignedBuffer a(static_cast<std::size_t>(s.m) * s.k), c(static_cast<std::size_t>(s.m) * s.n);
  fill(a.data(), a.size(), 4);
  fill(c.data(), c.size(), 5);
  const nn::ExecScope threads_scope(nn::with_threads(threads));
  const nn::GemmEpilogue ep = p.epilogue(s, c.data(), s.n);
  for (auto _ : state) {
    nn::gemm_parallel(s.m, a.data(), s.k, p.w, c.data(), s.n, ep);
    benchmark::ClobberMemory();
  }
  nnbench::set_flop_counters(state, 2.0 * s.m * s.n * s.k, threads);
}

void bm_tiles(benchmark::State& state, GemmShape s, int ukernel, int threads) {
  IsaOverride isa(ukernel == kBf16 ? nn::Isa::Avx512 : nn::gemm_ukernel(ukernel).isa);
  const Problem p(s, ukernel);
  // Per thread: one 64-row A tile and C tile, reused (hot in cache as in the fused loop).
  const std::size_t a_floats = static_cast<std::size_t>(kTileRows) * s.k;
  const std::size_t c_floats = static_cast<std::size_t>(kTileRows) * s.n;
  nn::AlignedBuffer a(a_floats * threads), c(c_floats * threads);
  fill(a.data(), a.size(), 6);
  fill(c.data(), c.size(), 7);
  std::vector<nn::bf16> ab(a.size());  // every ConvNeXt K is even: no pad needed
  if (ukernel == kBf16) nn::convert_to_bf16(kTileRows * threads, s.k, a.data(), s.k, ab.data(), s.k);
  const nn::ExecScope threads_scope(nn::with_threads(threads));
  for (auto _ : state) {
    nn::parallel_team(threads, [&](int t, int) {
      const float* at = a.data() + a_floats * t;
      float* ct = c.data() + c_floats * t;
      const nn::GemmEpilogue ep = p.epilogue(s, ct, s.n);
      if (ukernel == kBf16) {
        const nn::bf16* abt = ab.data() + a_floats * t;
        for (int i = 0; i < kTilesPerIteration; ++i) nn::gemm_bf16(kTileRows, abt, s.k, p.wb, ct, s.n, ep);
      } else {
        for (int i = 0; i < kTilesPerIteration; ++i) nn::gemm(kTileRows, at, s.k, p.w, ct, s.n, ep);
      }
    });
    benchmark::ClobberMemory();
  }
  nnbench::set_flop_counters(
      state, 2.0 * kTileRows * kTilesPerIteration * threads * s.n * s.k, threads);
}

int register_all() {
  for (int u = 0; u < nn::gemm_ukernel_count(); ++u) {
    const nn::GemmUkernelInfo& info = nn::gemm_ukernel(u);
    if (!nn::isa_supported(info.isa)) continue;
    for (const GemmShape& s : kShapes)
      for (int threads : {1, 2}) {
        const std::string suffix =
            std::string(s.name) + "/" + info.name + "/threads:" + std::to_string(threads);
        benchmark::RegisterBenchmark(("gemm/" + suffix).c_str(), bm_full, s, u, threads)
            ->UseRealTime()
            ->Unit(benchmark::kMillisecond);
        benchmark::RegisterBenchmark(("gemm_tile64/" + suffix).c_str(), bm_tiles, s, u, threads)
            ->UseRealTime()
            ->Unit(benchmark::kMicrosecond);
      }
  }
  if (nn::bf16_gemm_available())
    for (const GemmShape& s : kShapes)
      for (int threads : {1, 2})
        benchmark::RegisterBenchmark(("gemm_tile64/" + std::string(s.name) + "/" + nn::gemm_bf16_kernel_name() +
                                      "/threads:" + std::to_string(threads)).c_str(),
                                     bm_tiles, s, kBf16, threads)
            ->UseRealTime()
            ->Unit(benchmark::kMicrosecond);
  return 0;
}

const int kRegistered = register_all();

}  // namespace
