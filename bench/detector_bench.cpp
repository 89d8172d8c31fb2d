// Faster R-CNN (torchvision layout, seeded random weights, 2 classes) on one
// 720x1280 frame: whole forward and, as counters, the mean ms of each stage
// (transform, backbone, FPN, RPN, RoI heads with post-processing). detectron2's
// R50-FPN (one class, as SHLE's) on the same frame as RGB8, next to torchvision's
// ResNet-50 FPN: the two should be within 10 % (docs/PERFORMANCE.md).
#include <benchmark/benchmark.h>

#include <map>
#include <memory>

#include "nn/models/detection/detectron2_faster_rcnn.h"
#include "nn/models/detection/faster_rcnn.h"
#include "nn/models/synthetic_weights.h"
#include "nn/threads.h"

namespace {

namespace det = nn::detection;

const weights::SafeTensors& detector_weights(det::FasterRcnnVariant v) {
  static std::map<int, weights::SafeTensors> cache;
  auto it = cache.find(static_cast<int>(v));
  if (it == cache.end())
    it = cache.emplace(static_cast<int>(v),
                       weights::SafeTensors::from_bytes(
                           nn::synthetic_weights(det::faster_rcnn_tensor_specs(v, 2), 11).bytes(),
                           std::string("synthetic ") + det::faster_rcnn_name(v)))
             .first;
  return it->second;
}

void BM_FasterRcnn(benchmark::State& state) {
  const auto v = static_cast<det::FasterRcnnVariant>(state.range(0));
  const int threads = static_cast<int>(state.range(1));
  const int h = 720, w = 1280;
  nn::set_num_threads(threads);
  det::FasterRcnn model(detector_weights(v), v);
  model.plan(h, w);
  nn::SplitMix64 rng(3);
  std::vector<float> x(static_cast<std::size_t>(3) * h * w);
  for (auto& e : x) e = static_cast<float>(rng.uniform());
  model.forward(x.data());  // warm-up: first touch of every buffer
  model.profiler().set_enabled(true);
  model.profiler().reset_times();
  for (auto _ : state) benchmark::DoNotOptimize(model.forward(x.data()).boxes.data());
  for (const auto& e : model.profiler().entries())
    if (e.calls > 0) state.counters[e.layer + "_ms"] = e.total_ms / e.calls;
  state.SetLabel(det::faster_rcnn_name(v));
  nn::set_num_threads(0);
}

BENCHMARK(BM_FasterRcnn)
    ->ArgNames({"variant", "threads"})
    ->Args({static_cast<int>(det::FasterRcnnVariant::MobileNetV3LargeFpn), 2})
    ->Args({static_cast<int>(det::FasterRcnnVariant::MobileNetV3Large320Fpn), 2})
    ->Args({static_cast<int>(det::FasterRcnnVariant::ResNet50Fpn), 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(2.0);

void BM_Detectron2FasterRcnn(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  const int h = 720, w = 1280;
  static const weights::SafeTensors weights = weights::SafeTensors::from_bytes(
      nn::synthetic_weights(det::detectron2_faster_rcnn_tensor_specs(2), 11).bytes(), "synthetic detectron2");
  nn::set_num_threads(threads);
  // Random weights on 0-255 inputs saturate the RPN (a handful of image-sized
  // proposals, an idle box head); detectron2's other common PIXEL_STD (torchvision's,
  // times 255) brings the input to unit scale, so the RPN and the box head do the
  // work of a trained model (1000 proposals), as in the torchvision benchmark.
  det::Detectron2FasterRcnnConfig cfg;
  cfg.transform.std[0] = 57.375f, cfg.transform.std[1] = 57.12f, cfg.transform.std[2] = 58.395f;
  det::Detectron2FasterRcnn model(weights, cfg);
  model.plan(h, w);
  nn::SplitMix64 rng(3);
  std::vector<std::uint8_t> rgb(static_cast<std::size_t>(3) * h * w);
  for (auto& e : rgb) e = static_cast<std::uint8_t>(rng.next() & 255);
  model.forward(rgb.data());  // warm-up: first touch of every buffer
  model.profiler().set_enabled(true);
  model.profiler().reset_times();
  for (auto _ : state) benchmark::DoNotOptimize(model.forward(rgb.data()).boxes.data());
  for (const auto& e : model.profiler().entries())
    if (e.calls > 0) state.counters[e.layer + "_ms"] = e.total_ms / e.calls;
  state.counters["proposals"] = static_cast<double>(model.proposals().boxes.size());
  state.SetLabel(det::kDetectron2FasterRcnnName);
  nn::set_num_threads(0);
}

BENCHMARK(BM_Detectron2FasterRcnn)
    ->ArgNames({"threads"})
    ->Args({2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(2.0);

}  // namespace
