// The detectors' 3x3 stride-1 convolutions at 720x1280 input (768x1344 padded), direct
// (im2col + GEMM) against Winograd F(4x4, 3x3), per ISA, 2 threads. GFLOP/s and
// pct_peak count the direct form's multiply-adds (2 * 9 * C_in * C_out per output
// pixel) for both, so Winograd's figure is an effective rate and may exceed the peak.
#include <benchmark/benchmark.h>

#include <vector>

#include "bench/peak.h"
#include "bench/random_data.h"
#include "nn/conv2d.h"
#include "nn/isa.h"
#include "nn/threads.h"
#include "nn/winograd.h"

namespace {

void BM_Conv3x3(benchmark::State& state) {
  const int h = static_cast<int>(state.range(0)), w = static_cast<int>(state.range(1));
  const int cin = static_cast<int>(state.range(2)), cout = static_cast<int>(state.range(3));
  const bool winograd = state.range(4) != 0;
  const auto isa = static_cast<nn::Isa>(state.range(5));
  const int threads = 2;
  if (!nn::isa_supported(isa)) {
    state.SkipWithError("ISA not supported by this CPU");
    return;
  }
  nn::set_isa(isa);
  nn::set_num_threads(threads);
  nn::Conv2dParams p;
  p.cin = cin, p.cout = cout, p.kh = p.kw = 3, p.pad_h = p.pad_w = 1;
  const nn::Shape in{1, h, w, cin}, out{1, h, w, cout};
  nnbench::UniformStream u;
  const std::vector<float> x = u.vector(in.count()), wt = u.vector(static_cast<std::size_t>(cout) * cin * 9, 0.05f),
                           b = u.vector(cout);
  std::vector<float> y(out.count());
  const bool saved = nn::winograd_enabled();
  nn::set_winograd(winograd);
  const nn::Conv2dWeights packed = nn::Conv2dWeights::pack(wt.data(), b.data(), p);
  nn::set_winograd(saved);
  nn::AlignedBuffer scratch(nn::conv2d_scratch_floats(packed, w) * threads + 16);
  for (auto _ : state) {
    nn::conv2d(nn::ConstTensorView(x.data(), in), packed, nn::TensorView{y.data(), out}, scratch.data(), nn::Act::Relu);
    benchmark::ClobberMemory();
  }
  nnbench::set_flop_counters(state, 2.0 * 9 * cin * cout * static_cast<double>(h) * w, threads);
  state.SetLabel(std::string(nn::isa_name(isa)) + (winograd ? " winograd" : " direct"));
  nn::set_num_threads(0);
  nn::set_isa(nn::detect_isa());
}

void shapes(benchmark::internal::Benchmark* b) {
  // {h, w, cin, cout}: ResNet-50 layer1..layer4 conv2, FPN / RPN at strides 4 and 16,
  // MobileNetV3's FPN / RPN at stride 32.
  const int layers[][4] = {{192, 336, 64, 64},   {96, 168, 128, 128}, {48, 84, 256, 256}, {24, 42, 512, 512},
                           {192, 336, 256, 256}, {48, 84, 256, 256},  {24, 42, 256, 256}};
  for (const auto& l : layers)
    for (int wino : {0, 1})
      for (nn::Isa isa : {nn::Isa::Avx512, nn::Isa::Avx2})
        b->Args({l[0], l[1], l[2], l[3], wino, static_cast<int>(isa)});
}

BENCHMARK(BM_Conv3x3)->Apply(shapes)->ArgNames({"h", "w", "cin", "cout", "wino", "isa"})->UseRealTime()->Unit(benchmark::kMillisecond);

}  // namespace
