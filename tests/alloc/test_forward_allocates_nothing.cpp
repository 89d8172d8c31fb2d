// llama2.c discipline: models plan their memory once; forward() performs no heap
// allocation. Every operator new in this binary is counted while forward runs.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>

#include "nn/gemm_bf16.h"
#include "nn/models/convnext.h"
#include "nn/models/detection/faster_rcnn.h"
#include "nn/models/stixel_head.h"
#include "nn/models/stixelnext.h"
#include "nn/models/synthetic_weights.h"
#include "nn/threads.h"

namespace {
std::atomic<long> g_allocations{0};
std::atomic<bool> g_counting{false};
}  // namespace

void* operator new(std::size_t n) {
  if (g_counting) {
    ++g_allocations;
    // ROADNN_ALLOC_ABORT=1 stops at the offending allocation, so gdb's backtrace names it.
    if (std::getenv("ROADNN_ALLOC_ABORT")) std::abort();
  }
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) { return operator new(n); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }

namespace {

void benchmark_sink(volatile float* p) { p[0] = 1.0f; }

nn::ConvNeXtConfig small() { return {{8, 12, 20, 28}, {1, 1, 2, 1}}; }

long allocations_during(const std::function<void()>& f) {
  g_allocations = 0;
  g_counting = true;
  f();
  g_counting = false;
  return g_allocations;
}

// The counter itself works (otherwise the tests below could not fail).
TEST(NoAllocation, CounterSeesAllocations) {
  EXPECT_GE(allocations_during([] { std::vector<float> v(1000); benchmark_sink(v.data()); }), 1);
}

TEST(NoAllocation, ConvNeXtForward) {
  auto st = weights::SafeTensors::from_bytes(
      nn::synthetic_weights(nn::convnext_tensor_specs(small(), "features."), 1).bytes(), "synthetic");
  for (int threads : {1, 2}) {
    nn::set_num_threads(threads);
    nn::ConvNeXt model(st);
    model.plan(2, 96, 128);
    std::vector<float> x(2 * 3 * 96 * 128, 0.5f);
    model.forward(x.data());  // warm-up: OpenMP starts its team
    EXPECT_EQ(0, allocations_during([&] { model.forward(x.data()); })) << threads << " threads";
    model.profiler().set_enabled(true);
    EXPECT_EQ(0, allocations_during([&] { model.forward(x.data()); })) << "profiling, " << threads << " threads";
  }
  nn::set_num_threads(0);
}

TEST(NoAllocation, ConvNeXtForwardBf16) {
  if (!nn::bf16_gemm_available()) GTEST_SKIP() << "this CPU has no AVX512_BF16";
  auto st = weights::SafeTensors::from_bytes(
      nn::synthetic_weights(nn::convnext_tensor_specs(small(), "features."), 1).bytes(), "synthetic");
  for (int threads : {1, 2}) {
    nn::set_num_threads(threads);
    nn::ConvNeXt model(st, "features.", nn::Precision::Bf16);
    model.plan(2, 96, 128);
    std::vector<float> x(2 * 3 * 96 * 128, 0.5f);
    model.forward(x.data());
    EXPECT_EQ(0, allocations_during([&] { model.forward(x.data()); })) << threads << " threads";
  }
  nn::set_num_threads(0);
}

TEST(NoAllocation, StixelNExTForwardEveryHead) {
  for (auto v : {nn::StixelHeadVariant::V4, nn::StixelHeadVariant::V1, nn::StixelHeadVariant::V0}) {
    auto specs = nn::convnext_tensor_specs(small(), "features.");
    for (auto& s : nn::stixel_head_tensor_specs(v, 28, "classifier.")) specs.push_back(s);
    auto st = weights::SafeTensors::from_bytes(nn::synthetic_weights(specs, 2).bytes(), "synthetic");
    nn::StixelNExT model(st, v);
    model.plan(1, 64, 256, 32);
    std::vector<float> x(3 * 64 * 256, 100.f);
    model.forward(x.data());
    EXPECT_EQ(0, allocations_during([&] { model.forward(x.data()); })) << nn::stixel_head_name(v);
  }
}

// The detector's whole forward, post-processing included: with the score thresholds
// at 0 every stage (top-k, NMS on both paths, class-wise decoding) has work to do.
TEST(NoAllocation, FasterRcnnForwardEveryVariant) {
  namespace det = nn::detection;
  for (auto v : {det::FasterRcnnVariant::MobileNetV3Large320Fpn, det::FasterRcnnVariant::ResNet50Fpn}) {
    auto st = weights::SafeTensors::from_bytes(
        nn::synthetic_weights(det::faster_rcnn_tensor_specs(v, 3), 5).bytes(), "synthetic");
    det::FasterRcnnConfig cfg = det::faster_rcnn_defaults(v);
    cfg.transform.min_size = 160, cfg.transform.max_size = 256;
    cfg.rpn.score_thresh = 0.0f;
    cfg.roi_heads.score_thresh = 0.0f;
    for (int threads : {1, 2}) {
      nn::set_num_threads(threads);
      det::FasterRcnn model(st, v, cfg);
      model.plan(120, 200);
      std::vector<float> x(3 * 120 * 200);
      for (std::size_t i = 0; i < x.size(); ++i) x[i] = static_cast<float>((i * 7919) % 1000) / 1000.0f;
      model.forward(x.data());
      ASSERT_GT(model.proposals().boxes.size(), 100u) << "the test needs work for NMS";
      ASSERT_GT(model.forward(x.data()).boxes.size(), 0u) << "the test needs detections";
      EXPECT_EQ(0, allocations_during([&] { model.forward(x.data()); }))
          << det::faster_rcnn_name(v) << ", " << threads << " threads";
    }
  }
  nn::set_num_threads(0);
}

}  // namespace
