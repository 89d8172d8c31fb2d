// Depthwise convolution on the real models' layer shapes, per ISA and thread count:
// ConvNeXt-Tiny's 7x7 stages at 1280x1920 input, MobileNetV3-Large's 3x3 / 5x5
// layers at 720x1280. FLOPs count 2 per tap per output element (2*49 for 7x7).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <vector>

#include "bench/peak.h"
#include "bench/random_data.h"
#include "nn/dwconv.h"
#include "nn/isa.h"
#include "nn/threads.h"

namespace {

// A seeded layer: input [1, h, w, c] and packed weights, values in [-1, 1).
struct RandomDwLayer {
  nn::Shape in;
  std::vector<float> x;
  nn::DwConvWeights packed;
};

RandomDwLayer random_dw_layer(int h, int w, int c, const nn::DwConvParams& p) {
  RandomDwLayer l{nn::Shape{1, h, w, c}, {}, {}};
  nnbench::UniformStream u;
  l.x = u.vector(l.in.count());
  const std::vector<float> wt = u.vector(static_cast<std::size_t>(c) * p.kh * p.kw), b = u.vector(c);
  l.packed = nn::DwConvWeights::pack(wt.data(), b.data(), c, p);
  return l;
}

void BM_DwConv(benchmark::State& state) {
  const int h = static_cast<int>(state.range(0)), w = static_cast<int>(state.range(1));
  const int c = static_cast<int>(state.range(2)), k = static_cast<int>(state.range(3));
  const int stride = static_cast<int>(state.range(4));
  const auto isa = static_cast<nn::Isa>(state.range(5));
  const int threads = static_cast<int>(state.range(6));
  if (!nn::isa_supported(isa)) {
    state.SkipWithError("ISA not supported by this CPU");
    return;
  }
  nn::set_isa(isa);
  nn::set_num_threads(threads);

  nn::DwConvParams p;
  p.kh = p.kw = k;
  p.stride_h = p.stride_w = stride;
  p.pad_h = p.pad_w = k / 2;
  // ConvNeXt's depthwise conv has no activation; MobileNetV3's fuse one.
  p.act = stride == 1 && k == 7 ? nn::Act::None : nn::Act::HardSwish;
  const RandomDwLayer l = random_dw_layer(h, w, c, p);
  const nn::Shape& in = l.in;
  const std::vector<float>& x = l.x;
  const nn::DwConvWeights& packed = l.packed;
  const nn::Shape out = nn::dwconv_output_shape(in, p);
  std::vector<float> y(out.count());

  nn::dwconv(nn::ConstTensorView(x.data(), in), packed, nn::TensorView{y.data(), out});
  for (auto _ : state) {
    nn::dwconv(nn::ConstTensorView(x.data(), in), packed, nn::TensorView{y.data(), out});
    benchmark::ClobberMemory();
  }
  nnbench::set_flop_counters(state, 2.0 * k * k * static_cast<double>(out.count()), threads);
  const double bytes = (static_cast<double>(in.count()) + out.count()) * sizeof(float);
  state.counters["GB/s"] = benchmark::Counter(bytes * state.iterations() / 1e9, benchmark::Counter::kIsRate);
  state.SetLabel(nn::isa_name(isa));
  nn::set_num_threads(0);
  nn::set_isa(nn::detect_isa());
}

// ConvNeXt's banded blocks (nn/models/convnext.cpp, run_block_banded): one thread walks
// the image in bands of `band` output rows with dwconv_rows into a small buffer, the
// input coming from memory as in the model (the block input is far larger than L2).
void BM_DwConvBands(benchmark::State& state) {
  const int h = static_cast<int>(state.range(0)), w = static_cast<int>(state.range(1));
  const int c = static_cast<int>(state.range(2)), band = static_cast<int>(state.range(3));
  const auto isa = static_cast<nn::Isa>(state.range(4));
  if (!nn::isa_supported(isa)) {
    state.SkipWithError("ISA not supported by this CPU");
    return;
  }
  nn::set_isa(isa);
  nn::DwConvParams p;
  p.kh = p.kw = 7;
  p.pad_h = p.pad_w = 3;
  const RandomDwLayer l = random_dw_layer(h, w, c, p);
  std::vector<float> y(static_cast<std::size_t>(band) * w * c);
  const nn::ConstTensorView xv(l.x.data(), l.in);
  for (auto _ : state) {
    for (int y0 = 0; y0 < h; y0 += band)
      nn::dwconv_rows(xv, l.packed, 0, y0, std::min(h, y0 + band), y.data());
    benchmark::ClobberMemory();
  }
  nnbench::set_flop_counters(state, 2.0 * 49 * static_cast<double>(l.in.count()), 1);
  state.SetLabel(nn::isa_name(isa));
  nn::set_isa(nn::detect_isa());
}

BENCHMARK(BM_DwConvBands)
    ->ArgNames({"h", "w", "c", "band", "isa"})
    ->ArgsProduct({{320}, {480}, {96}, {8}, {1, 2}})
    ->Args({160, 240, 192, 8, 2})
    ->Args({80, 120, 384, 8, 2})
    // In L2 (a 16 x 60 x 96 input is 368 KB): the register kernel and the ring fills
    // without the wait on memory, on both ISAs.
    ->ArgsProduct({{16}, {60}, {16, 96}, {8}, {1, 2}})
    // Microseconds: the in-L2 shapes take 9-110 us. With --benchmark_repetitions=N also
    // the fastest repetition, the figure other tenants of a shared host move least.
    ->ComputeStatistics("min",
                        [](const std::vector<double>& v) { return *std::min_element(v.begin(), v.end()); })
    ->Unit(benchmark::kMicrosecond)
    ->UseRealTime()
    ->MinTime(0.5);

void shapes(benchmark::internal::Benchmark* b) {
  // {h, w, c, k, stride} of the input.
  const int layers[][5] = {
      {320, 480, 96, 7, 1},  {160, 240, 192, 7, 1}, {80, 120, 384, 7, 1}, {40, 60, 768, 7, 1},
      {360, 640, 64, 3, 2},  {180, 320, 72, 3, 1},  {180, 320, 72, 5, 2}, {90, 160, 120, 5, 1},
      {90, 160, 240, 3, 2},  {45, 80, 672, 5, 2},
  };
  for (const auto& l : layers)
    for (int isa = 0; isa <= 2; ++isa)
      for (int threads : {1, 2}) b->Args({l[0], l[1], l[2], l[3], l[4], isa, threads});
}

BENCHMARK(BM_DwConv)
    ->ArgNames({"h", "w", "c", "k", "s", "isa", "threads"})
    ->Apply(shapes)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(0.5);

}  // namespace
