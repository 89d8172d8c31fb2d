// The paper's Table III runtime protocol: random [3, 1280, 1920] frames through the
// network and the extraction, time per frame; plus the whole frame as the
// stixelnext command runs it (network + extraction + 3D) next to the backbone alone.
#include <benchmark/benchmark.h>

#include <memory>

#include "bench/peak.h"
#include "nn/models/stixel_head.h"
#include "nn/models/stixelnext.h"
#include "nn/models/synthetic_weights.h"
#include "nn/threads.h"
#include "stixel/anchors.h"
#include "stixel/extract.h"
#include "stixel/projection.h"

namespace {

const weights::SafeTensors& v4_weights() {
  static const weights::SafeTensors st = [] {
    auto specs = nn::convnext_tensor_specs(nn::convnext_tiny_config(), "features.");
    for (auto& s : nn::stixel_head_tensor_specs(nn::StixelHeadVariant::V4, 768, "classifier.")) specs.push_back(s);
    return weights::SafeTensors::from_bytes(nn::synthetic_weights(specs, 1).bytes(), "synthetic stixelnext v4");
  }();
  return st;
}

std::vector<float> random_frame(std::uint64_t seed) {
  nn::SplitMix64 rng(seed);
  std::vector<float> x(static_cast<std::size_t>(3) * 1280 * 1920);
  for (auto& v : x) v = static_cast<float>(255.0 * rng.uniform());
  return x;
}

// stage: 0 = network + extraction (Table III), 1 = + 3D top points (the stixelnext frame)
void BM_StixelNExTFrame(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  const bool with_3d = state.range(1) != 0;
  nn::set_num_threads(threads);
  nn::StixelNExT model(v4_weights());
  model.plan(1, 1280, 1920, 240);
  const stixel::Anchors anchors = stixel::tangent_anchors();
  stixel::ExtractOptions opt;
  opt.threshold = 0.36;
  const stixel::Projection proj({2081.25f, 0, 954.13f, 0, 2081.25f, 664.49f, 0, 0, 1}, {});
  // New random frame each iteration, as in the paper's protocol; generated outside the timing.
  std::vector<float> frames[2] = {random_frame(1), random_frame(2)};
  model.forward(frames[0].data());
  std::size_t i = 0, stixels = 0;
  for (auto _ : state) {
    const float* pred = model.forward(frames[i++ % 2].data());
    stixel::StixelWorld world = stixel::extract(pred, 4, 64, 240, anchors, opt);
    if (with_3d) benchmark::DoNotOptimize(stixel::top_points(world, proj).data());
    stixels += world.stixels.size();
  }
  state.counters["stixels"] = static_cast<double>(stixels) / state.iterations();
  nnbench::set_flop_counters(state, model.backbone().flops(), threads);
  nn::set_num_threads(0);
}

BENCHMARK(BM_StixelNExTFrame)
    ->ArgNames({"threads", "with_3d"})
    ->Args({1, 0})
    ->Args({2, 0})
    ->Args({2, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(3.0);

}  // namespace
