// llama2.c discipline: models plan their memory once; forward() performs no heap
// allocation. Every operator new in this binary is counted while forward runs.
#include <gtest/gtest.h>

#include <atomic>
#include <cerrno>
#include <cstdlib>
#include <new>

#include "nn/gemm_bf16.h"
#include "nn/models/convnext.h"
#include "nn/models/detection/detectron2_faster_rcnn.h"
#include "nn/models/detection/faster_rcnn.h"
#include "nn/models/stixel_head.h"
#include "nn/models/stixelnext.h"
#include "nn/models/synthetic_weights.h"
#include "nn/threads.h"
#include "roadnn/roadnn.h"
#include "tests/counting_dump_sink.h"

namespace {
std::atomic<long> g_allocations{0};
std::atomic<bool> g_counting{false};

void count_allocation() {
  if (g_counting) {
    ++g_allocations;
    // ROADNN_ALLOC_ABORT=1 stops at the offending allocation, so gdb's backtrace names it.
    if (std::getenv("ROADNN_ALLOC_ABORT")) std::abort();
  }
}
}  // namespace

// The C allocator itself is interposed (glibc's own entry points do the work), so
// malloc/calloc/realloc/aligned_alloc/posix_memalign calls from C code, the C++ runtime or
// the engine's AlignedBuffer count too, not only operator new (which calls malloc).
extern "C" {
void* __libc_malloc(std::size_t);
void* __libc_calloc(std::size_t, std::size_t);
void* __libc_realloc(void*, std::size_t);
void* __libc_memalign(std::size_t, std::size_t);
void __libc_free(void*);

void* malloc(std::size_t n) {
  count_allocation();
  return __libc_malloc(n);
}
void* calloc(std::size_t n, std::size_t size) {
  count_allocation();
  return __libc_calloc(n, size);
}
void* realloc(void* p, std::size_t n) {
  count_allocation();
  return __libc_realloc(p, n);
}
void* aligned_alloc(std::size_t align, std::size_t n) {
  count_allocation();
  return __libc_memalign(align, n);
}
void* memalign(std::size_t align, std::size_t n) {
  count_allocation();
  return __libc_memalign(align, n);
}
int posix_memalign(void** out, std::size_t align, std::size_t n) {
  count_allocation();
  void* p = __libc_memalign(align, n);
  if (!p) return ENOMEM;
  *out = p;
  return 0;
}
void free(void* p) { __libc_free(p); }
}

void* operator new(std::size_t n) {
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
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
  EXPECT_GE(allocations_during([] {
              void* p = std::aligned_alloc(64, 4096);
              benchmark_sink(static_cast<float*>(p));
              std::free(p);
            }),
            1);
  EXPECT_GE(allocations_during([] {
              void* p = std::malloc(100);
              benchmark_sink(static_cast<float*>(p));
              std::free(p);
            }),
            1);
}

TEST(NoAllocation, ConvNeXtForward) {
  auto st = weights::SafeTensors::from_bytes(
      nn::synthetic_weights(nn::convnext_tensor_specs(small(), "features."), 1).bytes(), "synthetic");
  for (int threads : {1, 2}) {
    nn::set_num_threads(threads);
    nn::ConvNeXt model(st);
    model.plan(2, 96, 128);
    std::vector<float> x(2 * 3 * 96 * 128, 0.5f);
    model.forward(x.data());  // warm-up: starts this thread's pool workers
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

// detectron2's R50-FPN: the Pillow resize, adaptive RoIAlign's sample room (planned
// per thread) and the rescale to the original image included.
TEST(NoAllocation, Detectron2FasterRcnnForward) {
  namespace det = nn::detection;
  auto st = weights::SafeTensors::from_bytes(
      nn::synthetic_weights(det::detectron2_faster_rcnn_tensor_specs(3), 5).bytes(), "synthetic");
  det::Detectron2FasterRcnnConfig cfg;
  cfg.transform.min_size = 160, cfg.transform.max_size = 256;
  // Random weights on 0-255 inputs saturate the RPN (one image-sized proposal):
  // detectron2's other common PIXEL_STD brings the input to unit scale.
  cfg.transform.std[0] = 57.375f, cfg.transform.std[1] = 57.12f, cfg.transform.std[2] = 58.395f;
  cfg.roi_heads.score_thresh = 0.0f;
  for (int threads : {1, 2}) {
    nn::set_num_threads(threads);
    det::Detectron2FasterRcnn model(st, cfg);
    model.plan(120, 200);
    std::vector<std::uint8_t> x(3 * 120 * 200);
    for (std::size_t i = 0; i < x.size(); ++i) x[i] = static_cast<std::uint8_t>((i * 7919) % 251);
    model.forward(x.data());
    ASSERT_GT(model.proposals().boxes.size(), 100u) << "the test needs work for NMS";
    ASSERT_GT(model.forward(x.data()).boxes.size(), 0u) << "the test needs detections";
    EXPECT_EQ(0, allocations_during([&] { model.forward(x.data()); })) << threads << " threads";
  }
  nn::set_num_threads(0);
}

}  // namespace

// Through the C API: a session's run allocates nothing either (after its first run,
// which sizes the detector's input staging and result arrays).
namespace {

struct ApiModel {
  roadnn_model* model = nullptr;
  roadnn_session* session = nullptr;
  ~ApiModel() {
    roadnn_session_free(session);
    roadnn_model_free(model);
  }
};

TEST(NoAllocation, CApiConvNeXtRun) {
  const auto bytes = nn::synthetic_weights(nn::convnext_tensor_specs(small(), "features."), 1).bytes();
  for (int threads : {1, 2}) {
    ApiModel m;
    const roadnn_model_params mp = roadnn_model_default_params(ROADNN_MODEL_CONVNEXT);
    ASSERT_EQ(ROADNN_OK, roadnn_model_load_memory(bytes.data(), bytes.size(), &mp, &m.model)) << roadnn_last_error();
    roadnn_session_params sp = roadnn_session_default_params();
    sp.threads = threads;
    sp.height = 96, sp.width = 128;
    ASSERT_EQ(ROADNN_OK, roadnn_session_create(m.model, &sp, &m.session)) << roadnn_last_error();
    std::int64_t shape[4];
    ASSERT_EQ(ROADNN_OK, roadnn_convnext_output_shape(m.session, shape));
    std::vector<float> x(3 * 96 * 128, 0.5f), y(shape[0] * shape[1] * shape[2] * shape[3]);
    ASSERT_EQ(ROADNN_OK, roadnn_convnext_run(m.session, x.data(), x.size(), y.data(), y.size()));
    EXPECT_EQ(0, allocations_during([&] { roadnn_convnext_run(m.session, x.data(), x.size(), y.data(), y.size()); }))
        << threads << " threads";
  }
}

TEST(NoAllocation, CApiDetectRun) {
  namespace det = nn::detection;
  const auto v = det::FasterRcnnVariant::MobileNetV3Large320Fpn;
  const auto bytes = nn::synthetic_weights(det::faster_rcnn_tensor_specs(v, 3), 5).bytes();
  for (int threads : {1, 2}) {
    ApiModel m;
    roadnn_model_params mp = roadnn_model_default_params(ROADNN_MODEL_FASTERRCNN_MOBILENET_V3_LARGE_320_FPN);
    mp.box_score_thresh = 0.0f;
    ASSERT_EQ(ROADNN_OK, roadnn_model_load_memory(bytes.data(), bytes.size(), &mp, &m.model)) << roadnn_last_error();
    roadnn_session_params sp = roadnn_session_default_params();
    sp.threads = threads;
    sp.height = 120, sp.width = 200;
    ASSERT_EQ(ROADNN_OK, roadnn_session_create(m.model, &sp, &m.session)) << roadnn_last_error();
    std::vector<std::uint8_t> rgb(120 * 200 * 3);
    for (std::size_t i = 0; i < rgb.size(); ++i) rgb[i] = static_cast<std::uint8_t>((i * 7919) % 251);
    const roadnn_image image{rgb.data(), 200, 120, 0};
    roadnn_detections d;
    ASSERT_EQ(ROADNN_OK, roadnn_detect(m.session, &image, &d)) << roadnn_last_error();
    ASSERT_GT(d.count, 0u) << "the test needs detections";
    EXPECT_EQ(0, allocations_during([&] { roadnn_detect(m.session, &image, &d); })) << threads << " threads";
  }
}

}  // namespace

// Dumps (nn/dump.h): with the sink set the forward may allocate (names, layout
// conversion); switched off again, it allocates nothing, and the sink sees nothing.
namespace {

using testutil::CountingDumpSink;

TEST(NoAllocation, DumpSwitchedOffConvNeXtAndStixelNExT) {
  auto specs = nn::convnext_tensor_specs(small(), "features.");
  for (auto& s : nn::stixel_head_tensor_specs(nn::StixelHeadVariant::V4, 28, "classifier.")) specs.push_back(s);
  auto st = weights::SafeTensors::from_bytes(nn::synthetic_weights(specs, 2).bytes(), "synthetic");
  nn::StixelNExT model(st);
  model.plan(1, 64, 256, 32);
  std::vector<float> x(3 * 64 * 256, 100.f);
  CountingDumpSink sink;
  model.set_dump(&sink);
  model.forward(x.data());
  ASSERT_GT(sink.tensors, 10) << "the dump was on";
  model.set_dump(nullptr);
  const long seen = sink.tensors;
  EXPECT_EQ(0, allocations_during([&] { model.forward(x.data()); }));
  EXPECT_EQ(seen, sink.tensors);
}

TEST(NoAllocation, DumpSwitchedOffFasterRcnn) {
  namespace det = nn::detection;
  const auto v = det::FasterRcnnVariant::ResNet50Fpn;
  auto st = weights::SafeTensors::from_bytes(nn::synthetic_weights(det::faster_rcnn_tensor_specs(v, 3), 5).bytes(),
                                             "synthetic");
  det::FasterRcnnConfig cfg = det::faster_rcnn_defaults(v);
  cfg.transform.min_size = 160, cfg.transform.max_size = 256;
  det::FasterRcnn model(st, v, cfg);
  model.plan(120, 200);
  std::vector<float> x(3 * 120 * 200, 0.25f);
  CountingDumpSink sink;
  model.set_dump(&sink);
  model.forward(x.data());
  ASSERT_GT(sink.tensors, 50) << "the dump was on";
  model.set_dump(nullptr);
  const long seen = sink.tensors;
  EXPECT_EQ(0, allocations_during([&] { model.forward(x.data()); }));
  EXPECT_EQ(seen, sink.tensors);
}

void count_tensor(const char*, const std::int64_t*, int, const float*, const char*, void* user) {
  ++*static_cast<long*>(user);
}

TEST(NoAllocation, CApiDumpSwitchedOff) {
  const auto bytes = nn::synthetic_weights(nn::convnext_tensor_specs(small(), "features."), 1).bytes();
  ApiModel m;
  const roadnn_model_params mp = roadnn_model_default_params(ROADNN_MODEL_CONVNEXT);
  ASSERT_EQ(ROADNN_OK, roadnn_model_load_memory(bytes.data(), bytes.size(), &mp, &m.model)) << roadnn_last_error();
  roadnn_session_params sp = roadnn_session_default_params();
  sp.height = 96, sp.width = 128;
  ASSERT_EQ(ROADNN_OK, roadnn_session_create(m.model, &sp, &m.session)) << roadnn_last_error();
  std::int64_t shape[4];
  ASSERT_EQ(ROADNN_OK, roadnn_convnext_output_shape(m.session, shape));
  std::vector<float> x(3 * 96 * 128, 0.5f), y(shape[0] * shape[1] * shape[2] * shape[3]);
  long tensors = 0;
  ASSERT_EQ(ROADNN_OK, roadnn_session_set_dump(m.session, count_tensor, &tensors));
  ASSERT_EQ(ROADNN_OK, roadnn_convnext_run(m.session, x.data(), x.size(), y.data(), y.size()));
  ASSERT_GT(tensors, 5);
  ASSERT_EQ(ROADNN_OK, roadnn_session_set_dump(m.session, nullptr, nullptr));
  const long seen = tensors;
  EXPECT_EQ(0, allocations_during([&] { roadnn_convnext_run(m.session, x.data(), x.size(), y.data(), y.size()); }));
  EXPECT_EQ(seen, tensors);
}

}  // namespace
