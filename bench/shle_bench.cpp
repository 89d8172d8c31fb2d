// SHLE stage 2 (box -> height) on rendered 1280x720 synthetic frames, plus the
// .dat parser and one NCC tracker step. Target: stage 2 under 2 ms per frame.
#include <benchmark/benchmark.h>

#include <map>
#include <vector>

#include "shle/disparity_io.h"
#include "shle/height.h"
#include "shle/synth.h"
#include "shle/tracker.h"

namespace {

struct RenderedFrame {
  shle::DisparityMap disparity;
  shle::GrayImage gray, next_gray;
  shle::Box box;
  shle::Calibration calibration;
  std::vector<std::uint8_t> dat_bytes;
};

// Frame k of a bar drive from 70 m to 10 m in 1 m steps (distance 70 - k).
const RenderedFrame& frame_at(int k) {
  static std::map<int, RenderedFrame> cache;
  auto it = cache.find(k);
  if (it != cache.end()) return it->second;
  shle::synth::SceneSpec spec;
  spec.seed = 7;
  spec.start_distance = 70;
  spec.end_distance = 10;
  spec.frames = 61;
  shle::synth::Scene scene(spec);
  shle::synth::Frame f = scene.render(k);
  RenderedFrame r;
  r.calibration = scene.calibration();
  r.box = f.box;
  r.dat_bytes.resize(2 * f.disparity.size());
  for (std::size_t i = 0; i < f.disparity.size(); ++i) {
    r.dat_bytes[2 * i] = f.disparity[i] & 0xFF;
    r.dat_bytes[2 * i + 1] = f.disparity[i] >> 8;
  }
  r.disparity = shle::parse_dat(r.dat_bytes.data(), r.dat_bytes.size(), 1280, 720, 5, "bench");
  r.gray = shle::to_gray(f.image);
  r.next_gray = shle::to_gray(scene.render(k + 1).image);
  return cache.emplace(k, std::move(r)).first->second;
}

void BM_shle_stage2(benchmark::State& state) {
  const RenderedFrame& f = frame_at(static_cast<int>(state.range(0)));
  shle::HeightEstimator est(f.calibration, shle::HeightOptions{});
  shle::HeightResult r;
  for (auto _ : state) {
    r = est.estimate(f.disparity, f.box);
    benchmark::DoNotOptimize(r.height);
  }
  state.counters["distance_m"] = 70.0 - state.range(0);
  state.counters["points"] = static_cast<double>(r.points);
  state.counters["box_px"] = static_cast<double>((r.u1 - r.u0) * (r.v1 - r.v0));
}
BENCHMARK(BM_shle_stage2)->Arg(0)->Arg(40)->Arg(55)->Arg(59)->Unit(benchmark::kMicrosecond);

// Worst case: the whole 1280x720 frame as the box.
void BM_shle_stage2_whole_frame(benchmark::State& state) {
  const RenderedFrame& f = frame_at(40);
  shle::HeightEstimator est(f.calibration, shle::HeightOptions{});
  shle::HeightResult r;
  for (auto _ : state) {
    r = est.estimate(f.disparity, shle::Box{0, 0, 1280, 720});
    benchmark::DoNotOptimize(r.height);
  }
  state.counters["points"] = static_cast<double>(r.points);
}
BENCHMARK(BM_shle_stage2_whole_frame)->Unit(benchmark::kMicrosecond);

void BM_shle_parse_dat(benchmark::State& state) {
  const RenderedFrame& f = frame_at(40);
  for (auto _ : state) {
    shle::DisparityMap m = shle::parse_dat(f.dat_bytes.data(), f.dat_bytes.size(), 1280, 720, 5, "bench");
    benchmark::DoNotOptimize(m.d.data());
  }
}
BENCHMARK(BM_shle_parse_dat)->Unit(benchmark::kMicrosecond);

void BM_shle_ncc_track(benchmark::State& state) {
  const RenderedFrame& f = frame_at(static_cast<int>(state.range(0)));
  shle::NccTracker t;
  for (auto _ : state) {
    t.init(shle::view(f.gray), f.box);
    shle::Box b;
    benchmark::DoNotOptimize(t.update(shle::view(f.next_gray), &b));
  }
  state.counters["template_px"] = f.box.width() * f.box.height();
}
BENCHMARK(BM_shle_ncc_track)->Arg(0)->Arg(40)->Unit(benchmark::kMillisecond);

}  // namespace

namespace {

void BM_shle_mil_track(benchmark::State& state) {
  const RenderedFrame& f = frame_at(static_cast<int>(state.range(0)));
  shle::MilTracker t;
  t.init(shle::view(f.gray), f.box);
  for (auto _ : state) {
    shle::Box b;
    benchmark::DoNotOptimize(t.update(shle::view(f.next_gray), &b));
  }
  state.counters["template_px"] = f.box.width() * f.box.height();
}
BENCHMARK(BM_shle_mil_track)->Arg(0)->Arg(40)->Unit(benchmark::kMillisecond);

}  // namespace
