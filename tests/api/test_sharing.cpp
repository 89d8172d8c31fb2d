// One model shared by sessions on concurrent threads, thread counts, load_memory
// against load_file, and strided images: every case gives bitwise the results of
// one session run serially on contiguous pixels.
#include <atomic>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include "tests/api/api_util.h"

namespace {

using namespace apitest;

struct Image {
  std::vector<std::uint8_t> px;
  int w, h;
  roadnn_image view() const { return image_of(px, w, h); }
};

std::vector<Image> images(const std::vector<std::pair<int, int>>& sizes, unsigned seed) {
  std::vector<Image> out;
  for (auto [w, h] : sizes) out.push_back({pixels(w, h, seed++), w, h});
  return out;
}

// Runs `a` on one thread and `b` on another, each on its own session of one model
// (make_session), `iterations` times over their inputs, both threads started
// together; every output must equal the serial output of one session.
template <class In, class Out>
void expect_concurrent_equals_serial(const std::function<SessionPtr()>& make_session, const std::vector<In>& a,
                                     const std::vector<In>& b,
                                     const std::function<Out(roadnn_session*, const In&)>& run,
                                     const std::function<::testing::AssertionResult(const Out&, const Out&)>& same,
                                     int iterations) {
  std::vector<Out> want_a, want_b;
  {
    SessionPtr s = make_session();
    ASSERT_NE(s.get(), nullptr);
    for (const In& x : a) want_a.push_back(run(s.get(), x));
    for (const In& x : b) want_b.push_back(run(s.get(), x));
  }
  // The inputs must give different outputs, or mixing them up would go unnoticed.
  ASSERT_FALSE(same(want_a[0], want_b[0]));

  std::atomic<int> ready{0};
  std::vector<Out> got_a, got_b;
  auto worker = [&](const std::vector<In>& in, std::vector<Out>& got) {
    SessionPtr s = make_session();
    ++ready;
    while (ready.load() < 2) std::this_thread::yield();
    if (!s.get()) return;
    for (int it = 0; it < iterations; ++it)
      for (const In& x : in) got.push_back(run(s.get(), x));
  };
  std::thread ta(worker, std::cref(a), std::ref(got_a));
  std::thread tb(worker, std::cref(b), std::ref(got_b));
  ta.join();
  tb.join();
  ASSERT_EQ(got_a.size(), a.size() * iterations);
  ASSERT_EQ(got_b.size(), b.size() * iterations);
  for (std::size_t i = 0; i < got_a.size(); ++i) EXPECT_TRUE(same(got_a[i], want_a[i % a.size()])) << "A run " << i;
  for (std::size_t i = 0; i < got_b.size(); ++i) EXPECT_TRUE(same(got_b[i], want_b[i % b.size()])) << "B run " << i;
}

struct StixelInput {
  Image image;
  roadnn_camera camera;
};

std::vector<StixelInput> stixel_inputs(const std::vector<std::pair<int, int>>& sizes, unsigned seed) {
  std::vector<StixelInput> out;
  for (const Image& im : images(sizes, seed)) out.push_back({im, camera_for(im.w, im.h, (seed & 1) != 0)});
  return out;
}

StixelResult run_stixel_input(roadnn_session* s, const StixelInput& in) {
  const roadnn_stixel_params p = busy_stixel_params();
  return run_stixel(s, in.image.view(), &in.camera, &p);
}

// ---- two sessions of one model on two threads --------------------------------------

TEST(ApiSharing, ConvNeXtSessionsOnTwoThreads) {
  ModelPtr m = load_convnext();
  ASSERT_NE(m.get(), nullptr);
  const std::vector<std::vector<float>> a = {convnext_input(1), convnext_input(2)};
  const std::vector<std::vector<float>> b = {convnext_input(3), convnext_input(4), convnext_input(5)};
  expect_concurrent_equals_serial<std::vector<float>, std::vector<float>>([&] { return convnext_session(m.get()); }, a,
                                                                          b, run_convnext, same_floats, 6);
}

TEST(ApiSharing, StixelSessionsOnTwoThreads) {
  ModelPtr m = load_stixel();
  ASSERT_NE(m.get(), nullptr);
  // A at the network size, B at other sizes (resized, K scaled).
  const auto a = stixel_inputs({{kStixelW, kStixelH}, {kStixelW, kStixelH}}, 1);
  const auto b = stixel_inputs({{70, 50}, {150, 100}}, 4);
  // The comparisons need stixels with 3D points and clusters.
  {
    SessionPtr s = session(m.get());
    const StixelResult r = run_stixel_input(s.get(), a[0]);
    ASSERT_GT(r.stixels.size(), 3u);
    ASSERT_GE(r.world.clusters, 0);
    EXPECT_NE(r.stixels[0].top_point[2], 0.0);
    EXPECT_EQ(run_stixel_input(s.get(), b[0]).world.resized, 1);
  }
  expect_concurrent_equals_serial<StixelInput, StixelResult>([&] { return session(m.get()); }, a, b, run_stixel_input,
                                                             same_stixels, 4);
}

TEST(ApiSharing, DetectorSessionsOnTwoThreads) {
  const roadnn_model* m = shared_detector();
  ASSERT_NE(m, nullptr);
  // B's images have another size: its session plans again, the serial one each time.
  const auto a = images({{kDetW, kDetH}, {kDetW, kDetH}}, 1);
  const auto b = images({{112, 80}}, 3);
  auto run = [](roadnn_session* s, const Image& im) {
    auto d = run_detect(s, im.view());
    EXPECT_FALSE(d.empty());
    return d;
  };
  expect_concurrent_equals_serial<Image, std::vector<roadnn_detection>>([&] { return session(m); }, a, b, run,
                                                                        same_detections, 2);
}

// ---- thread counts -----------------------------------------------------------------

TEST(ApiThreads, OneAndTwoThreadsGiveTheSameBits) {
  ModelPtr cm = load_convnext(), sm = load_stixel();
  const roadnn_model* dm = shared_detector();
  ASSERT_TRUE(cm.get() && sm.get() && dm);
  const auto x = convnext_input(9);
  const auto st = stixel_inputs({{kStixelW, kStixelH}, {70, 50}}, 3);
  const auto det = images({{kDetW, kDetH}}, 5);
  SessionPtr c1 = convnext_session(cm.get(), 1), c2 = convnext_session(cm.get(), 2);
  SessionPtr s1 = session(sm.get(), 1), s2 = session(sm.get(), 2);
  SessionPtr d1 = session(dm, 1), d2 = session(dm, 2);
  EXPECT_TRUE(same_floats(run_convnext(c1.get(), x), run_convnext(c2.get(), x)));
  for (const auto& in : st) {
    const StixelResult r1 = run_stixel_input(s1.get(), in);
    EXPECT_FALSE(r1.stixels.empty());
    EXPECT_TRUE(same_stixels(r1, run_stixel_input(s2.get(), in)));
  }
  const auto r1 = run_detect(d1.get(), det[0].view());
  EXPECT_FALSE(r1.empty());
  EXPECT_TRUE(same_detections(r1, run_detect(d2.get(), det[0].view())));
}

// ---- load_memory ------------------------------------------------------------------

TEST(ApiLoadMemory, SameOutputsAsLoadFile) {
  // The caller's copy of the bytes may go away right after loading.
  auto from_temporary_copy = [](const std::vector<std::uint8_t>& bytes, roadnn_model_kind kind) {
    std::vector<std::uint8_t> copy = bytes;
    ModelPtr m = load_memory(copy, params(kind));
    std::fill(copy.begin(), copy.end(), 0xff);
    copy.clear();
    copy.shrink_to_fit();
    return m;
  };
  {
    ModelPtr f = load_convnext(), mem = from_temporary_copy(convnext_weights().bytes, ROADNN_MODEL_CONVNEXT);
    ASSERT_TRUE(f.get() && mem.get());
    SessionPtr a = convnext_session(f.get()), b = convnext_session(mem.get());
    for (unsigned seed : {1u, 2u}) {
      const auto x = convnext_input(seed);
      EXPECT_TRUE(same_floats(run_convnext(a.get(), x), run_convnext(b.get(), x)));
    }
    roadnn_model_info fi, mi;
    ASSERT_EQ(roadnn_model_get_info(f.get(), &fi), ROADNN_OK);
    ASSERT_EQ(roadnn_model_get_info(mem.get(), &mi), ROADNN_OK);
    EXPECT_EQ(fi.weight_bytes, mi.weight_bytes);
    EXPECT_STREQ(fi.kernels, mi.kernels);
  }
  {
    ModelPtr f = load_stixel(), mem = from_temporary_copy(stixel_weights().bytes, ROADNN_MODEL_STIXELNEXT);
    ASSERT_TRUE(f.get() && mem.get());
    roadnn_model_info mi;
    ASSERT_EQ(roadnn_model_get_info(mem.get(), &mi), ROADNN_OK);
    EXPECT_EQ(mi.input_height, kStixelH);  // the metadata read from memory too
    SessionPtr a = session(f.get()), b = session(mem.get());
    for (const auto& in : stixel_inputs({{kStixelW, kStixelH}, {150, 100}}, 7)) {
      const StixelResult r = run_stixel_input(a.get(), in);
      EXPECT_FALSE(r.stixels.empty());
      EXPECT_TRUE(same_stixels(r, run_stixel_input(b.get(), in)));
    }
  }
  {
    const roadnn_model* f = shared_detector();
    ModelPtr mem = from_temporary_copy(detector_weights().bytes, kDetKind);
    ASSERT_TRUE(f && mem.get());
    SessionPtr a = session(f), b = session(mem.get());
    const auto im = images({{kDetW, kDetH}}, 8);
    const auto r = run_detect(a.get(), im[0].view());
    EXPECT_FALSE(r.empty());
    EXPECT_TRUE(same_detections(r, run_detect(b.get(), im[0].view())));
  }
}

// ---- strided images ---------------------------------------------------------------

TEST(ApiStride, StixelStridedImagesGiveTheContiguousResult) {
  ModelPtr m = load_stixel();
  ASSERT_NE(m.get(), nullptr);
  SessionPtr s = session(m.get());
  const roadnn_stixel_params p = busy_stixel_params();
  for (auto [w, h] : {std::pair<int, int>{kStixelW, kStixelH}, {70, 50}}) {
    SCOPED_TRACE(std::to_string(w) + "x" + std::to_string(h));
    const auto px = pixels(w, h, 4);
    const roadnn_camera cam = camera_for(w, h, true);
    const StixelResult flat = run_stixel(s.get(), image_of(px, w, h), &cam, &p);
    ASSERT_FALSE(flat.stixels.empty());
    // stride == 3 * width is the contiguous call.
    EXPECT_TRUE(same_stixels(run_stixel(s.get(), image_of(px, w, h, 3 * w), &cam, &p), flat));
    for (std::size_t pad : {1, 13, 64}) {
      const auto padded = with_padding(px, w, h, pad);
      EXPECT_TRUE(same_stixels(run_stixel(s.get(), image_of(padded, w, h, 3 * w + pad), &cam, &p), flat))
          << "pad " << pad;
    }
    // Garbage in the pixels themselves does change the result (the test can fail).
    auto other = px;
    for (std::size_t i = 0; i < other.size(); i += 2) other[i] = static_cast<std::uint8_t>(255 - other[i]);
    EXPECT_FALSE(same_stixels(run_stixel(s.get(), image_of(other, w, h), &cam, &p), flat));
  }
}

TEST(ApiStride, DetectorStridedImagesGiveTheContiguousResult) {
  SessionPtr s = session(shared_detector());
  ASSERT_NE(s.get(), nullptr);
  const int w = kDetW, h = kDetH;
  const auto px = pixels(w, h, 6);
  const auto flat = run_detect(s.get(), image_of(px, w, h));
  ASSERT_FALSE(flat.empty());
  for (std::size_t pad : {1, 29}) {
    const auto padded = with_padding(px, w, h, pad);
    EXPECT_TRUE(same_detections(run_detect(s.get(), image_of(padded, w, h, 3 * w + pad)), flat)) << "pad " << pad;
  }
  auto other = px;
  for (std::size_t i = 0; i < other.size(); i += 2) other[i] = static_cast<std::uint8_t>(255 - other[i]);
  EXPECT_FALSE(same_detections(run_detect(s.get(), image_of(other, w, h)), flat));
}

}  // namespace
