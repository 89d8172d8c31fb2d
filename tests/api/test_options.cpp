// Per-model options in one process: models loaded with different ISA caps or
// Winograd choices run interleaved, each giving what the engine gives under an
// nn::ExecScope with that setting; the caller's own engine options and the
// environment change nothing.
#include <cstdlib>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "nn/exec.h"
#include "nn/isa.h"
#include "nn/layout.h"
#include "stixel/frame_pipeline.h"
#include "tests/api/api_util.h"

namespace {

using namespace apitest;
namespace det = nn::detection;

nn::ExecOptions exec(nn::Isa isa, bool winograd = true, int threads = 0) {
  nn::ExecOptions o;
  o.max_isa = isa;
  o.winograd = winograd;
  o.threads = threads;
  return o;
}

// ---- the engine's own results ------------------------------------------------------

std::vector<float> engine_convnext(nn::Isa isa, const std::vector<float>& x) {
  nn::ExecScope scope(exec(isa));
  const auto st = weights::SafeTensors::from_bytes(convnext_weights().bytes, "reference");
  nn::ConvNeXt m(st);
  m.plan(1, kConvH, kConvW);
  const nn::ConstTensorView y = m.forward(x.data());
  std::vector<float> out(y.count());
  nn::nhwc_to_nchw(y.data, y.shape.n, y.shape.c, y.shape.h, y.shape.w, out.data());
  return out;
}

// The engine's detector for (isa, winograd), loaded on first use and kept.
std::vector<roadnn_detection> engine_detect(nn::Isa isa, bool winograd, const std::vector<std::uint8_t>& px, int w,
                                            int h) {
  static std::map<std::pair<nn::Isa, bool>, std::unique_ptr<det::FasterRcnn>> models;
  nn::ExecScope scope(exec(isa, winograd));
  auto& m = models[{isa, winograd}];
  if (!m) {
    const auto st = weights::SafeTensors::from_bytes(detector_weights().bytes, "reference");
    m = std::make_unique<det::FasterRcnn>(st, kDetVariant, det::faster_rcnn_defaults(kDetVariant));
  }
  m->plan(h, w);
  // torchvision's input: planar RGB / 255.
  const std::size_t plane = static_cast<std::size_t>(w) * h;
  std::vector<float> x(3 * plane);
  for (std::size_t i = 0; i < plane; ++i)
    for (int c = 0; c < 3; ++c) x[c * plane + i] = px[3 * i + c] / 255.0f;
  const det::Detections& d = m->forward(x.data());
  std::vector<roadnn_detection> out(d.boxes.size());
  for (std::size_t i = 0; i < out.size(); ++i)
    out[i] = {d.boxes[i].x1, d.boxes[i].y1, d.boxes[i].x2, d.boxes[i].y2, d.scores[i], static_cast<int>(d.labels[i])};
  return out;
}

// process_frame on a Predictor of the same weights (metadata settings), with the
// camera and options busy_stixel_params() gives the API.
StixelResult engine_stixel(nn::Isa isa, const std::vector<std::uint8_t>& px, int w, int h, const roadnn_camera& cam) {
  nn::ExecScope scope(exec(isa));
  const auto st = weights::SafeTensors::from_bytes(stixel_weights().bytes, "reference");
  stixel::Predictor pred(st, stixel::settings_from_metadata(st.metadata(), "reference"));
  const roadnn_stixel_params p = busy_stixel_params();
  stixel::FrameOptions o;
  o.threshold = p.threshold;
  o.cluster = true;
  o.cluster_options.eps = p.cluster_eps;
  o.cluster_options.min_samples = p.cluster_min_samples;
  o.camera = stixel::FrameCamera{std::vector<float>(cam.K, cam.K + 9),
                                 cam.has_T ? std::vector<float>(cam.T, cam.T + 16) : std::vector<float>{}, "cam"};
  const stixel::FrameResult f = stixel::process_frame(pred, {px.data(), w, h, static_cast<std::size_t>(w) * 3}, o);
  StixelResult r;
  for (std::size_t i = 0; i < f.world.stixels.size(); ++i) {
    const stixel::Stixel& s = f.world.stixels[i];
    roadnn_stixel t;
    t.u = s.u, t.top = s.vT, t.bottom = s.vB, t.width = s.width, t.depth = s.d, t.confidence = s.confidence;
    t.cluster = s.cluster;
    const stixel::Point3 &a = f.top_points[i], &b = f.bottom_points[i];
    t.top_point[0] = a.x, t.top_point[1] = a.y, t.top_point[2] = a.z;
    t.bottom_point[0] = b.x, t.bottom_point[1] = b.y, t.bottom_point[2] = b.z;
    r.stixels.push_back(t);
  }
  r.world.count = r.stixels.size();
  r.world.clusters = f.world.context.clusters;
  r.world.image_width = kStixelW;
  r.world.image_height = kStixelH;
  for (int i = 0; i < 9; ++i) r.world.K[i] = f.network_K[i];
  r.world.resized = f.resized ? 1 : 0;
  return r;
}

std::string kernels_of(const roadnn_model* m) {
  roadnn_model_info info;
  EXPECT_EQ(roadnn_model_get_info(m, &info), ROADNN_OK) << roadnn_last_error();
  return info.kernels ? info.kernels : "(null)";
}

struct IsaCase {
  roadnn_isa api;
  nn::Isa engine;
};

// Scalar, each vector ISA of this build's architecture the CPU has, the other
// architecture's level-1 name (a cap is a level: neon on x86-64 runs AVX2, avx2 on
// aarch64 runs NEON) and the default.
std::vector<IsaCase> isa_cases() {
  std::vector<IsaCase> c = {{ROADNN_ISA_SCALAR, nn::Isa::Scalar}};
  const IsaCase vector_caps[] = {
      {ROADNN_ISA_AVX2, nn::Isa::Avx2}, {ROADNN_ISA_AVX512, nn::Isa::Avx512}, {ROADNN_ISA_NEON, nn::Isa::Neon}};
  for (const IsaCase& v : vector_caps)
    if (nn::isa_supported(v.engine)) c.push_back(v);
#if defined(__aarch64__)
  if (nn::isa_supported(nn::Isa::Neon)) c.push_back({ROADNN_ISA_AVX2, nn::Isa::Neon});
#elif defined(__x86_64__)
  if (nn::isa_supported(nn::Isa::Avx2)) c.push_back({ROADNN_ISA_NEON, nn::Isa::Avx2});
#endif
  c.push_back({ROADNN_ISA_BEST, nn::detect_isa()});
  return c;
}

// ---- ISA caps ----------------------------------------------------------------------

TEST(ApiOptions, ConvNeXtIsaCapsPerModelInOneProcess) {
  const auto cases = isa_cases();
  const std::vector<std::vector<float>> inputs = {convnext_input(1), convnext_input(2)};
  std::vector<ModelPtr> models;
  std::vector<SessionPtr> sessions;
  std::vector<std::vector<std::vector<float>>> want;  // [case][input]
  for (const IsaCase& c : cases) {
    roadnn_model_params p = params(ROADNN_MODEL_CONVNEXT);
    p.max_isa = c.api;
    models.push_back(load_convnext(p));
    ASSERT_NE(models.back().get(), nullptr);
    EXPECT_EQ(kernels_of(models.back().get()), nn::isa_name(c.engine));
    want.emplace_back();
    for (const auto& x : inputs) want.back().push_back(engine_convnext(c.engine, x));
  }
  // The sessions are made after every model is loaded, then run interleaved.
  for (const ModelPtr& m : models) sessions.push_back(convnext_session(m.get()));
  for (int round = 0; round < 3; ++round)
    for (std::size_t i = 0; i < inputs.size(); ++i)
      for (std::size_t k = 0; k < cases.size(); ++k) {
        SCOPED_TRACE(nn::isa_name(cases[k].engine) + std::string(" round ") + std::to_string(round));
        EXPECT_TRUE(same_floats(run_convnext(sessions[k].get(), inputs[i]), want[k][i]));
      }
  // The scalar path is not the vector one bit for bit, so a cap leaking from one
  // model into another would show above.
  if (nn::detect_isa() != nn::Isa::Scalar) {
    EXPECT_FALSE(same_floats(want[0][0], want.back()[0])) << "scalar and best give the same bits";
  }
}

// roadnn_model_info.kernels names the set that runs: by default the architecture's
// vector ISA (NEON on every aarch64 CPU), "scalar" when capped so.
TEST(ApiOptions, ReportedKernelsAreTheArchitecturesDefault) {
  ModelPtr best = load_convnext();
  ASSERT_NE(best.get(), nullptr);
  EXPECT_EQ(kernels_of(best.get()), nn::isa_name(nn::detect_isa()));
#if defined(__aarch64__)
  EXPECT_EQ(kernels_of(best.get()), "neon");
#elif defined(__x86_64__)
  EXPECT_NE(kernels_of(best.get()), "neon");
#endif
  roadnn_model_params p = params(ROADNN_MODEL_CONVNEXT);
  p.max_isa = ROADNN_ISA_SCALAR;
  ModelPtr scalar = load_convnext(p);
  ASSERT_NE(scalar.get(), nullptr);
  EXPECT_EQ(kernels_of(scalar.get()), "scalar");
}

TEST(ApiOptions, StixelIsaCapsGiveTheEnginePipeline) {
  const int w = 70, h = 50;
  const auto px = pixels(w, h, 3);
  const roadnn_camera cam = camera_for(w, h, true);
  const roadnn_stixel_params p = busy_stixel_params();
  std::vector<SessionPtr> sessions;
  std::vector<ModelPtr> models;
  std::vector<StixelResult> want;
  for (roadnn_isa cap : {ROADNN_ISA_SCALAR, ROADNN_ISA_BEST}) {
    roadnn_model_params mp = params(ROADNN_MODEL_STIXELNEXT);
    mp.max_isa = cap;
    models.push_back(load_stixel(mp));
    ASSERT_NE(models.back().get(), nullptr);
    sessions.push_back(session(models.back().get()));
    want.push_back(engine_stixel(cap == ROADNN_ISA_SCALAR ? nn::Isa::Scalar : nn::detect_isa(), px, w, h, cam));
    ASSERT_FALSE(want.back().stixels.empty());
  }
  EXPECT_EQ(kernels_of(models[0].get()), "scalar");
  for (int round = 0; round < 2; ++round)
    for (std::size_t k = 0; k < sessions.size(); ++k)
      EXPECT_TRUE(same_stixels(run_stixel(sessions[k].get(), image_of(px, w, h), &cam, &p), want[k]))
          << "model " << k << " round " << round;
}

// ---- Winograd ----------------------------------------------------------------------

// (The direct form is the slow one: it runs on one image only.)
TEST(ApiOptions, DetectorWinogradPerModelInOneProcess) {
  const auto a = pixels(kDetW, kDetH, 1), b = pixels(kDetW, kDetH, 9);
  roadnn_model_params p0 = params(kDetKind), p1 = params(kDetKind);
  p0.winograd = 0;
  p1.winograd = 1;
  // Loaded interleaved with the sessions, run interleaved.
  ModelPtr m0 = load_detector(p0);
  SessionPtr s0 = session(m0.get());
  ModelPtr m1 = load_detector(p1);
  SessionPtr s1 = session(m1.get());
  SessionPtr s0b = session(m0.get());
  ASSERT_TRUE(s0.get() && s1.get() && s0b.get());
  const nn::Isa isa = nn::detect_isa();
  const auto want0 = engine_detect(isa, false, a, kDetW, kDetH);
  const auto want1a = engine_detect(isa, true, a, kDetW, kDetH), want1b = engine_detect(isa, true, b, kDetW, kDetH);
  ASSERT_FALSE(want0.empty());
  ASSERT_FALSE(want1a.empty());
  EXPECT_FALSE(same_detections(want0, want1a)) << "Winograd gives the direct form's bits";
  const roadnn_image ia = image_of(a, kDetW, kDetH), ib = image_of(b, kDetW, kDetH);
  for (int round = 0; round < 2; ++round) {
    SCOPED_TRACE(round);
    const auto r0 = run_detect((round == 0 ? s0 : s0b).get(), ia);
    const auto r1 = run_detect(s1.get(), ia);
    EXPECT_FALSE(same_detections(r0, r1));
    EXPECT_TRUE(same_detections(r0, want0));
    EXPECT_TRUE(same_detections(r1, want1a));
    EXPECT_TRUE(same_detections(run_detect(s1.get(), ib), want1b));
  }
  // The first direct session again, after the Winograd one ran the other image.
  EXPECT_TRUE(same_detections(run_detect(s0.get(), ia), want0));
}

// ---- the caller's state ------------------------------------------------------------

// The calling thread's own engine options (an application using the internal
// libraries too) neither reach a model's runs nor get changed by them.
TEST(ApiOptions, CallersExecScopeNeitherLeaksInNorIsChanged) {
  const auto px = pixels(kDetW, kDetH, 4);
  const roadnn_image im = image_of(px, kDetW, kDetH);
  const auto x = convnext_input(5);
  ModelPtr cm = load_convnext();
  ASSERT_TRUE(cm.get() && shared_detector());
  SessionPtr cs = convnext_session(cm.get()), ds = session(shared_detector());
  const auto want_c = run_convnext(cs.get(), x);
  const auto want_d = run_detect(ds.get(), im);
  {
    nn::ExecScope mine(exec(nn::Isa::Scalar, false, 1));
    // Loading and making sessions inside the caller's scope changes nothing either.
    ModelPtr cm2 = load_convnext(), dm2 = load_detector();
    ASSERT_TRUE(cm2.get() && dm2.get());
    EXPECT_EQ(kernels_of(cm2.get()), nn::isa_name(nn::detect_isa()));
    SessionPtr cs2 = convnext_session(cm2.get()), ds2 = session(dm2.get());
    EXPECT_TRUE(same_floats(run_convnext(cs.get(), x), want_c));
    EXPECT_TRUE(same_floats(run_convnext(cs2.get(), x), want_c));
    EXPECT_TRUE(same_detections(run_detect(ds.get(), im), want_d));
    EXPECT_TRUE(same_detections(run_detect(ds2.get(), im), want_d));
    const nn::ExecOptions& now = nn::current_exec();
    EXPECT_EQ(now.max_isa, nn::Isa::Scalar);
    EXPECT_FALSE(now.winograd);
    EXPECT_EQ(now.threads, 1);
  }
  // And a scalar, one-thread model leaves the default options of the thread alone.
  roadnn_model_params p = params(ROADNN_MODEL_CONVNEXT);
  p.max_isa = ROADNN_ISA_SCALAR;
  p.winograd = 0;
  ModelPtr odd = load_convnext(p);
  SessionPtr os = convnext_session(odd.get(), 1);
  run_convnext(os.get(), x);
  const nn::ExecOptions& now = nn::current_exec();
  const nn::ExecOptions defaults;
  EXPECT_EQ(now.max_isa, defaults.max_isa);
  EXPECT_EQ(now.winograd, defaults.winograd);
  EXPECT_EQ(now.threads, defaults.threads);
}

// NN_ISA and NN_WINOGRAD are the apps' conventions: the library reads no environment.
TEST(ApiOptions, EnvironmentChangesNothing) {
  const auto px = pixels(kDetW, kDetH, 6);
  const roadnn_image im = image_of(px, kDetW, kDetH);
  const auto x = convnext_input(6);
  ASSERT_EQ(std::getenv("NN_ISA"), nullptr) << "run this test without NN_ISA set";
  ASSERT_EQ(std::getenv("NN_WINOGRAD"), nullptr) << "run this test without NN_WINOGRAD set";
  std::vector<float> want_c;
  std::vector<roadnn_detection> want_d;
  std::string want_kernels;
  {
    ModelPtr cm = load_convnext();
    ASSERT_TRUE(cm.get() && shared_detector());
    want_kernels = kernels_of(cm.get());
    SessionPtr cs = convnext_session(cm.get()), ds = session(shared_detector());
    want_c = run_convnext(cs.get(), x);
    want_d = run_detect(ds.get(), im);
  }
  // What the variables would select does differ from the defaults (so the
  // comparison below can fail).
  EXPECT_FALSE(same_detections(want_d, engine_detect(nn::detect_isa(), false, px, kDetW, kDetH)));
  if (nn::detect_isa() != nn::Isa::Scalar) {
    EXPECT_FALSE(same_floats(want_c, engine_convnext(nn::Isa::Scalar, x)));
  }
  ASSERT_EQ(::setenv("NN_ISA", "scalar", 1), 0);
  ASSERT_EQ(::setenv("NN_WINOGRAD", "0", 1), 0);
  struct Unset {
    ~Unset() {
      ::unsetenv("NN_ISA");
      ::unsetenv("NN_WINOGRAD");
    }
  } unset;
  ModelPtr cm = load_convnext(), dm = load_detector();
  ASSERT_TRUE(cm.get() && dm.get());
  EXPECT_EQ(kernels_of(cm.get()), want_kernels);
  EXPECT_EQ(kernels_of(dm.get()), want_kernels);
  SessionPtr cs = convnext_session(cm.get()), ds = session(dm.get());
  EXPECT_TRUE(same_floats(run_convnext(cs.get(), x), want_c));
  EXPECT_TRUE(same_detections(run_detect(ds.get(), im), want_d));
}

}  // namespace
