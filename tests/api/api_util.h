// Shared pieces of the C API tests: small synthetic models (ConvNeXt 8-12-20-28,
// StixelNExT++ on it with a V4 head at 64x96, Faster R-CNN MobileNetV3-Large-320-FPN
// with 3 classes), their weights as bytes and as temporary files, test images, and
// checks of statuses and messages.
#pragma once

#include <gtest/gtest.h>

#include "tests/strided_image.h"
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "nn/models/convnext.h"
#include "nn/models/detection/faster_rcnn.h"
#include "nn/models/stixel_head.h"
#include "nn/models/synthetic_weights.h"
#include "roadnn/roadnn.h"

namespace apitest {

constexpr int kStixelH = 64, kStixelW = 96;  // the StixelNExT++ network input
constexpr int kConvH = 64, kConvW = 96;      // the ConvNeXt sessions' input
constexpr int kDetH = 96, kDetW = 128;       // the detector images
constexpr int kDetClasses = 3;
constexpr nn::detection::FasterRcnnVariant kDetVariant = nn::detection::FasterRcnnVariant::MobileNetV3Large320Fpn;
constexpr roadnn_model_kind kDetKind = ROADNN_MODEL_FASTERRCNN_MOBILENET_V3_LARGE_320_FPN;

inline nn::ConvNeXtConfig small_convnext() { return {{8, 12, 20, 28}, {1, 1, 1, 1}}; }

// One model's weights: the bytes (for load_memory) and the same bytes in a file
// (removed at exit).
struct WeightFile {
  std::vector<std::uint8_t> bytes;
  std::string path;
  WeightFile(const std::string& name, const std::vector<weights::TensorSpec>& specs, std::uint64_t seed,
             const std::vector<std::pair<std::string, std::string>>& metadata = {}) {
    weights::Writer w = nn::synthetic_weights(specs, seed);
    for (const auto& [k, v] : metadata) w.set_metadata(k, v);
    bytes = w.bytes();
    path = temp_path(name);
    w.write(path);
  }
  ~WeightFile() { std::remove(path.c_str()); }
  WeightFile(const WeightFile&) = delete;
  WeightFile& operator=(const WeightFile&) = delete;

  static std::string temp_path(const std::string& name) {
    return testing::TempDir() + "roadnn_api_" + std::to_string(static_cast<long>(::getpid())) + "_" + name;
  }
};
inline std::string temp_path(const std::string& name) { return WeightFile::temp_path(name); }

// Each made on first use (the detector's 19 M weights take a moment), once per process.
inline const WeightFile& convnext_weights() {
  static const WeightFile f("convnext.safetensors", nn::convnext_tensor_specs(small_convnext(), "features."), 1);
  return f;
}
inline const WeightFile& stixel_weights() {
  static const WeightFile f = [] {
    auto specs = nn::convnext_tensor_specs(small_convnext(), "features.");
    for (auto& s : nn::stixel_head_tensor_specs(nn::StixelHeadVariant::V4, 28, "classifier.")) specs.push_back(s);
    // The network size comes from the weights' metadata, as for a real export.
    return WeightFile(
        "stixel.safetensors", specs, 5,
        {{"stixelnext.input_height", std::to_string(kStixelH)}, {"stixelnext.input_width", std::to_string(kStixelW)}});
  }();
  return f;
}
inline const WeightFile& detector_weights() {
  static const WeightFile f("detector.safetensors", nn::detection::faster_rcnn_tensor_specs(kDetVariant, kDetClasses),
                            7);
  return f;
}

// RAII over roadnn_model* / roadnn_session* for the tests (the C API, not roadnn.hpp,
// so that every status is checked here).
struct ModelPtr {
  roadnn_model* p = nullptr;
  ModelPtr() = default;
  explicit ModelPtr(roadnn_model* m) : p(m) {}
  ModelPtr(ModelPtr&& o) noexcept : p(o.p) { o.p = nullptr; }
  ModelPtr& operator=(ModelPtr&& o) noexcept {
    std::swap(p, o.p);
    return *this;
  }
  ~ModelPtr() { roadnn_model_free(p); }
  roadnn_model* get() const { return p; }
};
struct SessionPtr {
  roadnn_session* p = nullptr;
  SessionPtr() = default;
  explicit SessionPtr(roadnn_session* s) : p(s) {}
  SessionPtr(SessionPtr&& o) noexcept : p(o.p) { o.p = nullptr; }
  SessionPtr& operator=(SessionPtr&& o) noexcept {
    std::swap(p, o.p);
    return *this;
  }
  ~SessionPtr() { roadnn_session_free(p); }
  roadnn_session* get() const { return p; }
};

// Loads or fails the test (the message is roadnn_last_error()).
inline ModelPtr load_file(const std::string& path, const roadnn_model_params& p) {
  roadnn_model* m = nullptr;
  const roadnn_status s = roadnn_model_load_file(path.c_str(), &p, &m);
  EXPECT_EQ(s, ROADNN_OK) << roadnn_last_error();
  return ModelPtr(m);
}
inline ModelPtr load_memory(const std::vector<std::uint8_t>& bytes, const roadnn_model_params& p) {
  roadnn_model* m = nullptr;
  const roadnn_status s = roadnn_model_load_memory(bytes.data(), bytes.size(), &p, &m);
  EXPECT_EQ(s, ROADNN_OK) << roadnn_last_error();
  return ModelPtr(m);
}

inline roadnn_model_params params(roadnn_model_kind kind) { return roadnn_model_default_params(kind); }
inline ModelPtr load_convnext(roadnn_model_params p = params(ROADNN_MODEL_CONVNEXT)) {
  return load_file(convnext_weights().path, p);
}
inline ModelPtr load_stixel(roadnn_model_params p = params(ROADNN_MODEL_STIXELNEXT)) {
  return load_file(stixel_weights().path, p);
}
inline ModelPtr load_detector(roadnn_model_params p = params(kDetKind)) {
  return load_file(detector_weights().path, p);
}

// The default detector, loaded once per process for the tests that only run it.
inline const roadnn_model* shared_detector() {
  static const ModelPtr m = load_detector();
  return m.get();
}

inline SessionPtr session(const roadnn_model* m, int threads = 0, int height = 0, int width = 0, int batch = 1) {
  roadnn_session_params sp = roadnn_session_default_params();
  sp.threads = threads;
  sp.height = height;
  sp.width = width;
  sp.batch = batch;
  roadnn_session* s = nullptr;
  const roadnn_status st = roadnn_session_create(m, &sp, &s);
  EXPECT_EQ(st, ROADNN_OK) << roadnn_last_error();
  return SessionPtr(s);
}
inline SessionPtr convnext_session(const roadnn_model* m, int threads = 0, int batch = 1) {
  return session(m, threads, kConvH, kConvW, batch);
}

// RGB8 pixels with some structure, so the networks see more than noise.
inline std::vector<std::uint8_t> pixels(int w, int h, unsigned seed) {
  std::vector<std::uint8_t> px(static_cast<std::size_t>(w) * h * 3);
  for (std::size_t i = 0; i < px.size(); ++i)
    px[i] = static_cast<std::uint8_t>((i * (37 + seed) + i / 97 + (i / (3 * w)) * seed) % 251);
  return px;
}

using testutil::with_padding;

inline roadnn_image image_of(const std::vector<std::uint8_t>& px, int w, int h, std::size_t stride = 0) {
  roadnn_image im;
  im.data = px.data();
  im.width = w;
  im.height = h;
  im.stride = stride;
  return im;
}

// A ConvNeXt input [batch, 3, kConvH, kConvW] of seeded values.
inline std::vector<float> convnext_input(unsigned seed, int batch = 1) {
  std::vector<float> x(static_cast<std::size_t>(batch) * 3 * kConvH * kConvW);
  nn::SplitMix64 rng(seed);
  for (auto& v : x) v = static_cast<float>(rng.normal());
  return x;
}

// A standard camera for a w x h image: f = 0.8 w, and a T 1.5 m up, 0.3 m right.
inline roadnn_camera camera_for(int w, int h, bool with_t) {
  roadnn_camera c;
  std::memset(&c, 0, sizeof c);
  const double f = 0.8 * w;
  const double K[9] = {f, 0, (w - 1) / 2.0, 0, f * 1.01, (h - 1) / 2.0, 0, 0, 1};
  std::memcpy(c.K, K, sizeof K);
  const double T[16] = {1, 0, 0, -0.3, 0, 1, 0, 1.5, 0, 0, 1, 0, 0, 0, 0, 1};
  std::memcpy(c.T, T, sizeof T);
  c.has_T = with_t ? 1 : 0;
  return c;
}

// ---- results as plain values, compared bitwise ------------------------------------

struct StixelResult {
  std::vector<roadnn_stixel> stixels;
  roadnn_stixel_world world;  // its stixels pointer is not compared
};

inline bool same_bits(const void* a, const void* b, std::size_t n) { return std::memcmp(a, b, n) == 0; }

inline ::testing::AssertionResult same_stixels(const StixelResult& a, const StixelResult& b) {
  if (a.stixels.size() != b.stixels.size())
    return ::testing::AssertionFailure() << a.stixels.size() << " vs " << b.stixels.size() << " stixels";
  for (std::size_t i = 0; i < a.stixels.size(); ++i) {
    const roadnn_stixel &x = a.stixels[i], &y = b.stixels[i];
    if (!(x.u == y.u && x.top == y.top && x.bottom == y.bottom && x.width == y.width && x.cluster == y.cluster &&
          same_bits(&x.depth, &y.depth, sizeof x.depth) &&
          same_bits(&x.confidence, &y.confidence, sizeof x.confidence) &&
          same_bits(x.top_point, y.top_point, sizeof x.top_point) &&
          same_bits(x.bottom_point, y.bottom_point, sizeof x.bottom_point)))
      return ::testing::AssertionFailure() << "stixel " << i << " differs";
  }
  const roadnn_stixel_world &u = a.world, &v = b.world;
  if (u.count != v.count || u.clusters != v.clusters || u.image_width != v.image_width ||
      u.image_height != v.image_height || u.resized != v.resized || !same_bits(u.K, v.K, sizeof u.K))
    return ::testing::AssertionFailure() << "the worlds' fields differ";
  return ::testing::AssertionSuccess();
}

inline ::testing::AssertionResult same_detections(const std::vector<roadnn_detection>& a,
                                                  const std::vector<roadnn_detection>& b) {
  if (a.size() != b.size()) return ::testing::AssertionFailure() << a.size() << " vs " << b.size() << " detections";
  for (std::size_t i = 0; i < a.size(); ++i) {
    const roadnn_detection &x = a[i], &y = b[i];
    if (!(same_bits(&x.x1, &y.x1, 4) && same_bits(&x.y1, &y.y1, 4) && same_bits(&x.x2, &y.x2, 4) &&
          same_bits(&x.y2, &y.y2, 4) && same_bits(&x.score, &y.score, 4) && x.label == y.label))
      return ::testing::AssertionFailure() << "detection " << i << " differs";
  }
  return ::testing::AssertionSuccess();
}

inline ::testing::AssertionResult same_floats(const std::vector<float>& a, const std::vector<float>& b) {
  if (a.size() != b.size()) return ::testing::AssertionFailure() << a.size() << " vs " << b.size() << " floats";
  for (std::size_t i = 0; i < a.size(); ++i)
    if (!same_bits(&a[i], &b[i], sizeof(float)))
      return ::testing::AssertionFailure() << "element " << i << ": " << a[i] << " vs " << b[i];
  return ::testing::AssertionSuccess();
}

// ---- running through the C API (the calls must succeed) ----------------------------

inline std::vector<float> run_convnext(roadnn_session* s, const std::vector<float>& x) {
  int64_t shape[4] = {0, 0, 0, 0};
  EXPECT_EQ(roadnn_convnext_output_shape(s, shape), ROADNN_OK) << roadnn_last_error();
  std::vector<float> y(static_cast<std::size_t>(shape[0] * shape[1] * shape[2] * shape[3]));
  EXPECT_EQ(roadnn_convnext_run(s, x.data(), x.size(), y.data(), y.size()), ROADNN_OK) << roadnn_last_error();
  return y;
}

inline StixelResult run_stixel(roadnn_session* s, const roadnn_image& im, const roadnn_camera* cam,
                               const roadnn_stixel_params* p) {
  StixelResult r;
  std::memset(&r.world, 0, sizeof r.world);
  EXPECT_EQ(roadnn_stixel_run(s, &im, cam, p, &r.world), ROADNN_OK) << roadnn_last_error();
  if (r.world.count) r.stixels.assign(r.world.stixels, r.world.stixels + r.world.count);
  return r;
}

inline std::vector<roadnn_detection> run_detect(roadnn_session* s, const roadnn_image& im) {
  roadnn_detections d;
  d.items = nullptr;
  d.count = 0;
  EXPECT_EQ(roadnn_detect(s, &im, &d), ROADNN_OK) << roadnn_last_error();
  return std::vector<roadnn_detection>(d.items, d.items + d.count);
}

// Clustering with a camera and a low threshold, so that there are stixels, 3D points
// and clusters to compare.
inline roadnn_stixel_params busy_stixel_params() {
  roadnn_stixel_params p = roadnn_stixel_default_params();
  p.threshold = 0.05;
  p.cluster = 1;
  p.cluster_eps = 3.0;
  return p;
}

// ---- errors ------------------------------------------------------------------------

// roadnn_last_error() is one non-empty line of printable characters.
inline ::testing::AssertionResult is_one_line(const char* text) {
  if (!text) return ::testing::AssertionFailure() << "roadnn_last_error() is NULL";
  const std::string t = text;
  if (t.empty()) return ::testing::AssertionFailure() << "roadnn_last_error() is empty";
  for (unsigned char c : t)
    if (c < 0x20 || c == 0x7f) return ::testing::AssertionFailure() << "control character in '" << t << "'";
  return ::testing::AssertionSuccess();
}

// The call's status is `want` and the thread's message is one line containing `part`.
#define EXPECT_API_ERROR(call, want, part)                                                                           \
  do {                                                                                                               \
    const roadnn_status got_status_ = (call);                                                                        \
    EXPECT_EQ(got_status_, want) << #call << ": " << roadnn_status_name(got_status_) << ": " << roadnn_last_error(); \
    EXPECT_TRUE(::apitest::is_one_line(roadnn_last_error())) << #call;                                               \
    EXPECT_NE(std::string(roadnn_last_error()).find(part), std::string::npos)                                        \
        << #call << ": message '" << roadnn_last_error() << "' lacks '" << (part) << "'";                            \
  } while (0)

}  // namespace apitest
