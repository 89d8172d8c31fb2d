// Misuse of every C entry point (the SHLE ones aside): null pointers, wrong sizes,
// calls for another model kind, out-of-range options, unreadable and malformed
// weights. Each returns its documented status with a one-line message for the
// calling thread, leaves the out-pointers as documented and crashes nothing.
#include <sys/stat.h>

#include <atomic>
#include <cmath>
#include <fstream>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include "tests/api/api_util.h"

namespace {

using namespace apitest;

const double kNaN = std::numeric_limits<double>::quiet_NaN();

// Loads are expected to fail with `want`: *out comes back NULL (documented).
#define EXPECT_LOAD_FILE_ERROR(path, params, want, part)                       \
  do {                                                                         \
    roadnn_model* out_ = reinterpret_cast<roadnn_model*>(0x1);                 \
    EXPECT_API_ERROR(roadnn_model_load_file(path, params, &out_), want, part); \
    EXPECT_EQ(out_, nullptr);                                                  \
    roadnn_model_free(out_);                                                   \
  } while (0)
#define EXPECT_LOAD_MEMORY_ERROR(data, size, params, want, part)                       \
  do {                                                                                 \
    roadnn_model* out_ = reinterpret_cast<roadnn_model*>(0x1);                         \
    EXPECT_API_ERROR(roadnn_model_load_memory(data, size, params, &out_), want, part); \
    EXPECT_EQ(out_, nullptr);                                                          \
    roadnn_model_free(out_);                                                           \
  } while (0)

// Both loaders fail the same way on these bytes.
void expect_bad_bytes(const std::vector<std::uint8_t>& bytes, const roadnn_model_params& p, roadnn_status want,
                      const std::string& part, const std::string& name) {
  SCOPED_TRACE(name);
  EXPECT_LOAD_MEMORY_ERROR(bytes.data(), bytes.size(), &p, want, part);
  const std::string path = temp_path(name);
  {
    std::ofstream f(path, std::ios::binary);
    f.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  }
  EXPECT_LOAD_FILE_ERROR(path.c_str(), &p, want, part);
  std::remove(path.c_str());
}

TEST(ApiBasics, VersionAndStatusNames) {
  EXPECT_STREQ(roadnn_version(), "0.2.0");
  const roadnn_status all[] = {ROADNN_OK,
                               ROADNN_ERROR_INVALID_ARGUMENT,
                               ROADNN_ERROR_WRONG_MODEL,
                               ROADNN_ERROR_IO,
                               ROADNN_ERROR_BAD_MODEL,
                               ROADNN_ERROR_UNSUPPORTED,
                               ROADNN_ERROR_OUT_OF_MEMORY,
                               ROADNN_ERROR_INTERNAL};
  std::vector<std::string> names;
  for (roadnn_status s : all) {
    ASSERT_NE(roadnn_status_name(s), nullptr);
    EXPECT_TRUE(is_one_line(roadnn_status_name(s)));
    for (const auto& n : names) EXPECT_NE(n, roadnn_status_name(s)) << "two statuses share a name";
    names.emplace_back(roadnn_status_name(s));
  }
  EXPECT_STREQ(roadnn_status_name(ROADNN_OK), "ok");
  EXPECT_STREQ(roadnn_status_name(ROADNN_ERROR_INVALID_ARGUMENT), "invalid argument");
  EXPECT_STREQ(roadnn_status_name(static_cast<roadnn_status>(42)), "unknown status");
  EXPECT_STREQ(roadnn_status_name(static_cast<roadnn_status>(-1)), "unknown status");
}

TEST(ApiBasics, DefaultParamsAreTheDocumentedOnes) {
  for (roadnn_model_kind k :
       {ROADNN_MODEL_CONVNEXT, ROADNN_MODEL_STIXELNEXT, ROADNN_MODEL_FASTERRCNN_MOBILENET_V3_LARGE_FPN,
        ROADNN_MODEL_FASTERRCNN_MOBILENET_V3_LARGE_320_FPN, ROADNN_MODEL_FASTERRCNN_RESNET50_FPN}) {
    const roadnn_model_params p = roadnn_model_default_params(k);
    EXPECT_EQ(p.kind, k);
    EXPECT_EQ(p.max_isa, ROADNN_ISA_BEST);
    EXPECT_EQ(p.winograd, 1);
    EXPECT_EQ(p.precision, ROADNN_PRECISION_F32);
    EXPECT_EQ(p.stixel_head, -1);
    EXPECT_EQ(p.input_height, 0);
    EXPECT_EQ(p.input_width, 0);
    EXPECT_EQ(p.columns, 0);
    EXPECT_EQ(p.stixel_width, 0);
    EXPECT_EQ(p.anchors, nullptr);
    EXPECT_EQ(p.normalization, nullptr);
    EXPECT_LT(p.box_score_thresh, 0.0f);
  }
  const roadnn_session_params s = roadnn_session_default_params();
  EXPECT_EQ(s.threads, 0);
  EXPECT_EQ(s.height, 0);
  EXPECT_EQ(s.width, 0);
  EXPECT_EQ(s.batch, 1);
  const roadnn_stixel_params t = roadnn_stixel_default_params();
  EXPECT_EQ(t.threshold, 0.36);
  EXPECT_EQ(t.train_focal, 0.0);
  EXPECT_EQ(t.cluster, 0);
  EXPECT_EQ(t.cluster_eps, 1.42);
  EXPECT_EQ(t.cluster_min_samples, 2);
  EXPECT_EQ(t.axis_a, 0);
  EXPECT_EQ(t.axis_b, 2);
}

TEST(ApiMisuse, FreeNullIsANoOp) {
  roadnn_model_free(nullptr);
  roadnn_session_free(nullptr);
  EXPECT_EQ(roadnn_model_warning_count(nullptr), 0u);
  EXPECT_EQ(roadnn_model_warning(nullptr, 0), nullptr);
}

TEST(ApiMisuse, LoadNullPointers) {
  const roadnn_model_params p = params(ROADNN_MODEL_CONVNEXT);
  roadnn_model* m = nullptr;
  EXPECT_LOAD_FILE_ERROR(nullptr, &p, ROADNN_ERROR_INVALID_ARGUMENT, "path is null");
  EXPECT_LOAD_FILE_ERROR(convnext_weights().path.c_str(), nullptr, ROADNN_ERROR_INVALID_ARGUMENT, "params is null");
  EXPECT_API_ERROR(roadnn_model_load_file(convnext_weights().path.c_str(), &p, nullptr), ROADNN_ERROR_INVALID_ARGUMENT,
                   "out is null");
  EXPECT_LOAD_MEMORY_ERROR(nullptr, convnext_weights().bytes.size(), &p, ROADNN_ERROR_INVALID_ARGUMENT, "data is null");
  EXPECT_LOAD_MEMORY_ERROR(convnext_weights().bytes.data(), 0, &p, ROADNN_ERROR_INVALID_ARGUMENT, "size is 0");
  EXPECT_LOAD_MEMORY_ERROR(convnext_weights().bytes.data(), convnext_weights().bytes.size(), nullptr,
                           ROADNN_ERROR_INVALID_ARGUMENT, "params is null");
  EXPECT_API_ERROR(
      roadnn_model_load_memory(convnext_weights().bytes.data(), convnext_weights().bytes.size(), &p, nullptr),
      ROADNN_ERROR_INVALID_ARGUMENT, "out is null");
  // The same calls with every pointer valid succeed (so the errors above are the pointers').
  ASSERT_EQ(roadnn_model_load_file(convnext_weights().path.c_str(), &p, &m), ROADNN_OK) << roadnn_last_error();
  EXPECT_NE(m, nullptr);
  EXPECT_STREQ(roadnn_last_error(), "");
  roadnn_model_free(m);
  ASSERT_EQ(roadnn_model_load_memory(convnext_weights().bytes.data(), convnext_weights().bytes.size(), &p, &m),
            ROADNN_OK)
      << roadnn_last_error();
  EXPECT_NE(m, nullptr);
  roadnn_model_free(m);
}

TEST(ApiMisuse, LoadFileThatCannotBeRead) {
  const roadnn_model_params p = params(ROADNN_MODEL_CONVNEXT);
  const std::string missing = temp_path("does_not_exist.safetensors");
  EXPECT_LOAD_FILE_ERROR(missing.c_str(), &p, ROADNN_ERROR_IO, missing);
  EXPECT_LOAD_FILE_ERROR("", &p, ROADNN_ERROR_IO, "cannot open");
  const std::string dir = temp_path("a_directory");
  ASSERT_EQ(::mkdir(dir.c_str(), 0700), 0);
  EXPECT_LOAD_FILE_ERROR(dir.c_str(), &p, ROADNN_ERROR_IO, dir);
  ::rmdir(dir.c_str());
  // A control character in the path is escaped: the message stays one line.
  const std::string odd = temp_path("line\nbreak\x1b.safetensors");
  EXPECT_LOAD_FILE_ERROR(odd.c_str(), &p, ROADNN_ERROR_IO, "line\\x0abreak\\x1b");
  // A very long path gives a bounded message.
  const std::string longpath = "/nonexistent/" + std::string(5000, 'x');
  EXPECT_LOAD_FILE_ERROR(longpath.c_str(), &p, ROADNN_ERROR_IO, "/nonexistent/");
  EXPECT_LT(std::string(roadnn_last_error()).size(), 2000u);
}

// A file without read permission. Root reads it anyway, so this runs only as
// another user (e.g. `runuser -u nobody -- api_tests`).
TEST(ApiMisuse, LoadFileWithoutReadPermission) {
  // Root reads any file: then the load runs in a child that gives up root first (as
  // the unprivileged user "nobody"), so the test runs on CI too.
  const std::string path = temp_path("unreadable.safetensors");
  {
    std::ofstream f(path, std::ios::binary);
    f.write(reinterpret_cast<const char*>(convnext_weights().bytes.data()),
            static_cast<std::streamsize>(convnext_weights().bytes.size()));
  }
  ASSERT_EQ(::chmod(path.c_str(), 0), 0);
  const roadnn_model_params p = params(ROADNN_MODEL_CONVNEXT);
  if (::geteuid() != 0) {
    EXPECT_LOAD_FILE_ERROR(path.c_str(), &p, ROADNN_ERROR_IO, "cannot open for reading");
  } else {
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
      if (::setgid(65534) != 0 || ::setuid(65534) != 0) ::_exit(3);
      roadnn_model* m = nullptr;
      const roadnn_status st = roadnn_model_load_file(path.c_str(), &p, &m);
      const bool ok = st == ROADNN_ERROR_IO && m == nullptr &&
                      std::string(roadnn_last_error()).find("cannot open for reading") != std::string::npos;
      ::_exit(ok ? 0 : 4);
    }
    int status = 0;
    ASSERT_EQ(::waitpid(child, &status, 0), child);
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_NE(3, WEXITSTATUS(status)) << "could not become the user nobody";
    EXPECT_EQ(0, WEXITSTATUS(status)) << "an unreadable file did not give ROADNN_ERROR_IO 'cannot open for reading'";
  }
  std::remove(path.c_str());
}

TEST(ApiMisuse, LoadGarbageAndTruncatedWeights) {
  const roadnn_model_params p = params(ROADNN_MODEL_CONVNEXT);
  std::vector<std::uint8_t> garbage(4096);
  nn::SplitMix64 rng(3);
  for (auto& b : garbage) b = static_cast<std::uint8_t>(rng.next());
  expect_bad_bytes(garbage, p, ROADNN_ERROR_BAD_MODEL, "", "garbage");
  expect_bad_bytes(std::vector<std::uint8_t>(1, 0), p, ROADNN_ERROR_BAD_MODEL, "", "one_byte");
  const std::string text = "{\"not\": \"safetensors\"}";
  expect_bad_bytes(std::vector<std::uint8_t>(text.begin(), text.end()), p, ROADNN_ERROR_BAD_MODEL, "", "json");
  // A header length pointing past the end.
  std::vector<std::uint8_t> huge_header(16, 0);
  huge_header[0] = 0xff, huge_header[1] = 0xff, huge_header[7] = 0x7f;
  expect_bad_bytes(huge_header, p, ROADNN_ERROR_BAD_MODEL, "", "huge_header");
  // The real file cut in the length field, the header, the data and one byte short.
  const std::vector<std::uint8_t>& full = convnext_weights().bytes;
  for (std::size_t n : {std::size_t{4}, std::size_t{8}, std::size_t{40}, full.size() / 2, full.size() - 1}) {
    expect_bad_bytes(std::vector<std::uint8_t>(full.begin(), full.begin() + static_cast<std::ptrdiff_t>(n)), p,
                     ROADNN_ERROR_BAD_MODEL, "", "truncated_" + std::to_string(n));
  }
  // The memory loader names its source.
  EXPECT_LOAD_MEMORY_ERROR(full.data(), full.size() - 1, &p, ROADNN_ERROR_BAD_MODEL, "<memory>");
}

TEST(ApiMisuse, WeightsOfAnotherModelKindNameTheTensor) {
  struct Case {
    const WeightFile* file;
    roadnn_model_kind kind;
    const char* tensor;
  };
  const Case cases[] = {
      {&convnext_weights(), ROADNN_MODEL_STIXELNEXT, "classifier."},  // no head
      {&detector_weights(), ROADNN_MODEL_CONVNEXT, "features."},
      {&detector_weights(), ROADNN_MODEL_STIXELNEXT, "features."},
      {&convnext_weights(), kDetKind, "missing tensor 'roi_heads.box_predictor.cls_score.weight'"},
      {&stixel_weights(), ROADNN_MODEL_FASTERRCNN_MOBILENET_V3_LARGE_FPN, "missing tensor 'roi_heads."},
      {&detector_weights(), ROADNN_MODEL_FASTERRCNN_RESNET50_FPN, "backbone."},  // MobileNet weights, ResNet asked for
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(std::string(c.file->path) + " as kind " + std::to_string(c.kind));
    const roadnn_model_params p = params(c.kind);
    EXPECT_LOAD_FILE_ERROR(c.file->path.c_str(), &p, ROADNN_ERROR_BAD_MODEL, c.tensor);
    EXPECT_LOAD_MEMORY_ERROR(c.file->bytes.data(), c.file->bytes.size(), &p, ROADNN_ERROR_BAD_MODEL, c.tensor);
  }
}

TEST(ApiMisuse, BadModelParams) {
  struct Case {
    const WeightFile* file;
    roadnn_model_params p;
    const char* part;
  };
  std::vector<Case> cases;
  auto add = [&](const WeightFile& f, roadnn_model_kind kind, auto&& change, const char* part) {
    roadnn_model_params p = params(kind);
    change(p);
    cases.push_back({&f, p, part});
  };
  const roadnn_model_kind C = ROADNN_MODEL_CONVNEXT, S = ROADNN_MODEL_STIXELNEXT, D = kDetKind;
  add(
      convnext_weights(), static_cast<roadnn_model_kind>(0), [](auto&) {}, "kind");
  add(
      convnext_weights(), static_cast<roadnn_model_kind>(6), [](auto&) {}, "kind");
  add(
      convnext_weights(), C, [](auto& p) { p.max_isa = static_cast<roadnn_isa>(4); }, "max_isa");
  add(
      convnext_weights(), C, [](auto& p) { p.max_isa = static_cast<roadnn_isa>(-1); }, "max_isa");
  add(
      detector_weights(), D, [](auto& p) { p.max_isa = static_cast<roadnn_isa>(100); }, "max_isa");
  add(
      convnext_weights(), C, [](auto& p) { p.winograd = 2; }, "winograd");
  add(
      detector_weights(), D, [](auto& p) { p.winograd = -1; }, "winograd");
  add(
      convnext_weights(), C, [](auto& p) { p.precision = static_cast<roadnn_precision>(2); }, "precision");
  add(
      stixel_weights(), S, [](auto& p) { p.precision = static_cast<roadnn_precision>(-3); }, "precision");
  add(
      detector_weights(), D, [](auto& p) { p.precision = ROADNN_PRECISION_BF16; }, "bf16");
  add(
      detector_weights(), D, [](auto& p) { p.precision = static_cast<roadnn_precision>(7); }, "precision");
  add(
      detector_weights(), D, [](auto& p) { p.box_score_thresh = 2.0f; }, "box_score_thresh");
  add(
      detector_weights(), D, [](auto& p) { p.box_score_thresh = std::numeric_limits<float>::quiet_NaN(); },
      "box_score_thresh");
  add(
      stixel_weights(), S, [](auto& p) { p.stixel_head = 7; }, "stixel_head");
  add(
      stixel_weights(), S, [](auto& p) { p.stixel_head = -2; }, "stixel_head");
  add(
      stixel_weights(), S, [](auto& p) { p.input_height = 10, p.input_width = 96; }, "input_height");
  add(
      stixel_weights(), S, [](auto& p) { p.input_height = 64; }, "input_height");  // width left 0
  add(
      stixel_weights(), S, [](auto& p) { p.input_height = 64, p.input_width = 20000; }, "input_height");
  add(
      stixel_weights(), S, [](auto& p) { p.columns = -1; }, "columns");
  add(
      stixel_weights(), S, [](auto& p) { p.stixel_width = -8; }, "stixel_width");
  add(
      stixel_weights(), S, [](auto& p) { p.stixel_width = 2000; }, "stixel_width");
  add(
      stixel_weights(), S, [](auto& p) { p.input_height = 32, p.input_width = 32, p.stixel_width = 64; },
      "stixel width");
  add(
      stixel_weights(), S, [](auto& p) { p.anchors = "bogus"; }, "anchor");
  add(
      stixel_weights(), S, [](auto& p) { p.anchors = "linear:1,2"; }, "anchor");
  add(
      stixel_weights(), S, [](auto& p) { p.anchors = "linear:1,60,32"; }, "anchor");  // 32, the head has 64
  add(
      stixel_weights(), S, [](auto& p) { p.anchors = ""; }, "anchor");
  add(
      stixel_weights(), S, [](auto& p) { p.normalization = "bogus"; }, "normalization");
  add(
      stixel_weights(), S, [](auto& p) { p.normalization = ""; }, "normalization");
  for (const Case& c : cases) {
    SCOPED_TRACE(c.part);
    EXPECT_LOAD_FILE_ERROR(c.file->path.c_str(), &c.p, ROADNN_ERROR_INVALID_ARGUMENT, c.part);
    EXPECT_LOAD_MEMORY_ERROR(c.file->bytes.data(), c.file->bytes.size(), &c.p, ROADNN_ERROR_INVALID_ARGUMENT, c.part);
  }
  // The fields the cases change are fine at their documented values.
  roadnn_model_params ok = params(S);
  ok.stixel_head = 4, ok.input_height = 64, ok.input_width = 128, ok.columns = 16, ok.stixel_width = 8;
  ok.anchors = "linear:5,69,64", ok.normalization = "imagenet";
  ModelPtr m = load_file(stixel_weights().path, ok);
  ASSERT_NE(m.get(), nullptr);
  roadnn_model_info info;
  ASSERT_EQ(roadnn_model_get_info(m.get(), &info), ROADNN_OK);
  EXPECT_EQ(info.input_height, 64);
  EXPECT_EQ(info.input_width, 128);
  EXPECT_EQ(info.columns, 16);
  EXPECT_STREQ(info.stixel_head, "v4");
}

// bf16: detectors never; ConvNeXt and StixelNExT++ only with the avx512 kernels and
// AVX512_BF16 (UNSUPPORTED otherwise: capped here, so this is tested on every CPU).
TEST(ApiMisuse, Bf16NeedsAvx512Bf16) {
  for (roadnn_model_kind k : {ROADNN_MODEL_CONVNEXT, ROADNN_MODEL_STIXELNEXT}) {
    const WeightFile& f = k == ROADNN_MODEL_CONVNEXT ? convnext_weights() : stixel_weights();
    roadnn_model_params p = params(k);
    p.precision = ROADNN_PRECISION_BF16;
    for (roadnn_isa cap : {ROADNN_ISA_SCALAR, ROADNN_ISA_AVX2}) {
      p.max_isa = cap;
      EXPECT_LOAD_FILE_ERROR(f.path.c_str(), &p, ROADNN_ERROR_UNSUPPORTED, "bf16");
    }
  }
}

class ApiMisuseModels : public testing::Test {
 protected:
  static void SetUpTestSuite() {
    convnext_ = new ModelPtr(load_convnext());
    stixel_ = new ModelPtr(load_stixel());
    detector_ = shared_detector();
    cs_ = new SessionPtr(convnext_session(convnext_->get()));
    ss_ = new SessionPtr(session(stixel_->get()));
    ds_ = new SessionPtr(session(detector_));
  }
  static void TearDownTestSuite() {
    delete cs_;
    delete ss_;
    delete ds_;
    delete convnext_;
    delete stixel_;
    cs_ = ss_ = ds_ = nullptr;
    convnext_ = stixel_ = nullptr;
  }
  void SetUp() override {
    ASSERT_NE(convnext_->get(), nullptr);
    ASSERT_NE(stixel_->get(), nullptr);
    ASSERT_NE(detector_, nullptr);
    ASSERT_NE(cs_->get(), nullptr);
    ASSERT_NE(ss_->get(), nullptr);
    ASSERT_NE(ds_->get(), nullptr);
  }
  static ModelPtr *convnext_, *stixel_;
  static const roadnn_model* detector_;
  static SessionPtr *cs_, *ss_, *ds_;
};
ModelPtr* ApiMisuseModels::convnext_ = nullptr;
ModelPtr* ApiMisuseModels::stixel_ = nullptr;
const roadnn_model* ApiMisuseModels::detector_ = nullptr;
SessionPtr* ApiMisuseModels::cs_ = nullptr;
SessionPtr* ApiMisuseModels::ss_ = nullptr;
SessionPtr* ApiMisuseModels::ds_ = nullptr;

TEST_F(ApiMisuseModels, ModelInfo) {
  roadnn_model_info info;
  std::memset(&info, 0x5a, sizeof info);
  const roadnn_model_info before = info;
  EXPECT_API_ERROR(roadnn_model_get_info(nullptr, &info), ROADNN_ERROR_INVALID_ARGUMENT, "model is null");
  EXPECT_TRUE(same_bits(&info, &before, sizeof info)) << "out written on failure";
  EXPECT_API_ERROR(roadnn_model_get_info(convnext_->get(), nullptr), ROADNN_ERROR_INVALID_ARGUMENT, "out is null");

  ASSERT_EQ(roadnn_model_get_info(convnext_->get(), &info), ROADNN_OK);
  EXPECT_EQ(info.kind, ROADNN_MODEL_CONVNEXT);
  EXPECT_GT(info.weight_bytes, 0u);
  EXPECT_EQ(info.num_classes, 0);
  EXPECT_EQ(info.input_height, 0);
  EXPECT_EQ(info.columns, 0);
  EXPECT_STREQ(info.stixel_head, "");
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(info.stage_widths[i], small_convnext().dims[i]) << i;
    EXPECT_EQ(info.stage_depths[i], small_convnext().depths[i]) << i;
  }
  ASSERT_EQ(roadnn_model_get_info(stixel_->get(), &info), ROADNN_OK);
  EXPECT_EQ(info.stage_widths[3], small_convnext().dims[3]) << "the backbone's configuration";
  EXPECT_EQ(info.stage_depths[3], small_convnext().depths[3]);
  EXPECT_EQ(info.kind, ROADNN_MODEL_STIXELNEXT);
  EXPECT_EQ(info.input_height, kStixelH);  // from the metadata
  EXPECT_EQ(info.input_width, kStixelW);
  EXPECT_EQ(info.columns, kStixelW / 8);
  EXPECT_STREQ(info.stixel_head, "v4");
  EXPECT_EQ(info.num_classes, 0);
  ASSERT_EQ(roadnn_model_get_info(detector_, &info), ROADNN_OK);
  EXPECT_EQ(info.kind, kDetKind);
  EXPECT_EQ(info.num_classes, kDetClasses);
  EXPECT_EQ(info.input_height, 0);
  EXPECT_EQ(info.stage_widths[0], 0);
  EXPECT_EQ(info.stage_depths[3], 0);
  EXPECT_GT(info.weight_bytes, 0u);
}

TEST_F(ApiMisuseModels, Warnings) {
  EXPECT_EQ(roadnn_model_warning_count(convnext_->get()), 0u);
  EXPECT_EQ(roadnn_model_warning(convnext_->get(), 0), nullptr);
  EXPECT_EQ(roadnn_model_warning_count(stixel_->get()), 0u);
  // StixelNExT++ weights as a ConvNeXt load (the backbone) and warn of the head.
  ModelPtr m = load_file(stixel_weights().path, params(ROADNN_MODEL_CONVNEXT));
  ASSERT_NE(m.get(), nullptr);
  ASSERT_EQ(roadnn_model_warning_count(m.get()), 1u);
  const char* text = roadnn_model_warning(m.get(), 0);
  EXPECT_TRUE(is_one_line(text));
  EXPECT_NE(std::string(text).find("classifier."), std::string::npos) << text;
  EXPECT_EQ(roadnn_model_warning(m.get(), 1), nullptr);
  EXPECT_EQ(roadnn_model_warning(m.get(), static_cast<size_t>(-1)), nullptr);
}

TEST_F(ApiMisuseModels, SessionCreate) {
  const roadnn_session_params dp = roadnn_session_default_params();
  roadnn_session* s = reinterpret_cast<roadnn_session*>(0x1);
  EXPECT_API_ERROR(roadnn_session_create(nullptr, &dp, &s), ROADNN_ERROR_INVALID_ARGUMENT, "model is null");
  EXPECT_EQ(s, nullptr);
  s = reinterpret_cast<roadnn_session*>(0x1);
  EXPECT_API_ERROR(roadnn_session_create(stixel_->get(), nullptr, &s), ROADNN_ERROR_INVALID_ARGUMENT, "params is null");
  EXPECT_EQ(s, nullptr);
  EXPECT_API_ERROR(roadnn_session_create(stixel_->get(), &dp, nullptr), ROADNN_ERROR_INVALID_ARGUMENT, "out is null");

  struct Case {
    const roadnn_model* model;
    int threads, height, width, batch;
    const char* part;
  };
  const Case cases[] = {
      {stixel_->get(), -1, 0, 0, 1, "threads"},
      {stixel_->get(), 1025, 0, 0, 1, "threads"},
      {convnext_->get(), 1, kConvH, kConvW, 0, "batch"},
      {convnext_->get(), 1, kConvH, kConvW, -2, "batch"},
      {convnext_->get(), 1, kConvH, kConvW, 5000, "batch"},
      {convnext_->get(), 1, 10, kConvW, 1, "height"},
      {convnext_->get(), 1, kConvH, 10, 1, "height"},
      {convnext_->get(), 1, 0, 0, 1, "height"},  // ConvNeXt sessions need a size
      {convnext_->get(), 1, kConvH, 20000, 1, "height"},
      {detector_, 1, 10, 128, 1, "height"},
      {detector_, 1, 96, 0, 1, "height"},
      {detector_, 1, -1, -1, 1, "height"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(std::string(c.part) + " " + std::to_string(c.threads) + " " + std::to_string(c.height) + "x" +
                 std::to_string(c.width) + " batch " + std::to_string(c.batch));
    roadnn_session_params p = dp;
    p.threads = c.threads, p.height = c.height, p.width = c.width, p.batch = c.batch;
    s = reinterpret_cast<roadnn_session*>(0x1);
    EXPECT_API_ERROR(roadnn_session_create(c.model, &p, &s), ROADNN_ERROR_INVALID_ARGUMENT, c.part);
    EXPECT_EQ(s, nullptr);
  }
  // StixelNExT++ ignores height/width/batch; detectors may plan ahead.
  SessionPtr a = session(stixel_->get(), 1, 7, 3, 0);
  EXPECT_NE(a.get(), nullptr);
  SessionPtr b = session(detector_, 1, kDetH, kDetW);
  EXPECT_NE(b.get(), nullptr);
}

TEST_F(ApiMisuseModels, ConvNeXtRunChecksEveryArgument) {
  roadnn_session* s = cs_->get();
  int64_t shape[4] = {-7, -7, -7, -7};
  EXPECT_API_ERROR(roadnn_convnext_output_shape(nullptr, shape), ROADNN_ERROR_INVALID_ARGUMENT, "session is null");
  EXPECT_EQ(shape[0], -7);
  EXPECT_API_ERROR(roadnn_convnext_output_shape(s, nullptr), ROADNN_ERROR_INVALID_ARGUMENT, "shape is null");
  ASSERT_EQ(roadnn_convnext_output_shape(s, shape), ROADNN_OK) << roadnn_last_error();
  EXPECT_EQ(shape[0], 1);
  EXPECT_EQ(shape[1], 28);
  EXPECT_EQ(shape[2], kConvH / 32);
  EXPECT_EQ(shape[3], kConvW / 32);
  const std::size_t out_count = static_cast<std::size_t>(shape[0] * shape[1] * shape[2] * shape[3]);

  const std::vector<float> x = convnext_input(1);
  std::vector<float> y(out_count + 1, -123.0f);
  auto untouched = [&] {
    for (float v : y)
      if (v != -123.0f) return false;
    return true;
  };
  EXPECT_API_ERROR(roadnn_convnext_run(nullptr, x.data(), x.size(), y.data(), out_count), ROADNN_ERROR_INVALID_ARGUMENT,
                   "session is null");
  EXPECT_API_ERROR(roadnn_convnext_run(s, nullptr, x.size(), y.data(), out_count), ROADNN_ERROR_INVALID_ARGUMENT,
                   "input is null");
  EXPECT_API_ERROR(roadnn_convnext_run(s, x.data(), x.size(), nullptr, out_count), ROADNN_ERROR_INVALID_ARGUMENT,
                   "output is null");
  EXPECT_API_ERROR(roadnn_convnext_run(s, x.data(), x.size() - 1, y.data(), out_count), ROADNN_ERROR_INVALID_ARGUMENT,
                   "input_count is " + std::to_string(x.size() - 1));
  EXPECT_API_ERROR(roadnn_convnext_run(s, x.data(), x.size() + 1, y.data(), out_count), ROADNN_ERROR_INVALID_ARGUMENT,
                   "input_count");
  EXPECT_API_ERROR(roadnn_convnext_run(s, x.data(), 0, y.data(), out_count), ROADNN_ERROR_INVALID_ARGUMENT,
                   "input_count");
  EXPECT_API_ERROR(roadnn_convnext_run(s, x.data(), x.size(), y.data(), out_count - 1), ROADNN_ERROR_INVALID_ARGUMENT,
                   "output_count is " + std::to_string(out_count - 1));
  EXPECT_API_ERROR(roadnn_convnext_run(s, x.data(), x.size(), y.data(), out_count + 1), ROADNN_ERROR_INVALID_ARGUMENT,
                   "output_count");
  EXPECT_TRUE(untouched()) << "the output was written by a failing call";
  // Right sizes: it runs and writes exactly output_count floats.
  ASSERT_EQ(roadnn_convnext_run(s, x.data(), x.size(), y.data(), out_count), ROADNN_OK) << roadnn_last_error();
  EXPECT_STREQ(roadnn_last_error(), "");
  EXPECT_EQ(y[out_count], -123.0f);
  for (std::size_t i = 0; i < out_count; ++i) ASSERT_TRUE(std::isfinite(y[i])) << i;

  // A batch of 2 wants twice the input.
  SessionPtr s2 = convnext_session(convnext_->get(), 1, 2);
  ASSERT_NE(s2.get(), nullptr);
  std::vector<float> y2(2 * out_count);
  EXPECT_API_ERROR(roadnn_convnext_run(s2.get(), x.data(), x.size(), y2.data(), y2.size()),
                   ROADNN_ERROR_INVALID_ARGUMENT, "[2, 3, 64, 96]");
  const std::vector<float> x2 = convnext_input(1, 2);
  EXPECT_EQ(roadnn_convnext_run(s2.get(), x2.data(), x2.size(), y2.data(), y2.size()), ROADNN_OK)
      << roadnn_last_error();
}

TEST_F(ApiMisuseModels, CallsForAnotherModelKind) {
  const auto px = pixels(kDetW, kDetH, 1);
  const roadnn_image im = image_of(px, kDetW, kDetH);
  const std::vector<float> x = convnext_input(1);
  std::vector<float> y(1 * 28 * 2 * 3);
  int64_t shape[4] = {-7, -7, -7, -7};
  roadnn_stixel_world world;
  roadnn_detections dets;
  std::memset(&world, 0x5a, sizeof world);
  std::memset(&dets, 0x5a, sizeof dets);
  const roadnn_stixel_world world0 = world;
  const roadnn_detections dets0 = dets;
  for (roadnn_session* s : {ss_->get(), ds_->get()}) {
    EXPECT_API_ERROR(roadnn_convnext_output_shape(s, shape), ROADNN_ERROR_WRONG_MODEL, "not a ConvNeXt");
    EXPECT_EQ(shape[0], -7);
    EXPECT_API_ERROR(roadnn_convnext_run(s, x.data(), x.size(), y.data(), y.size()), ROADNN_ERROR_WRONG_MODEL,
                     "roadnn_convnext_run");
  }
  EXPECT_API_ERROR(roadnn_stixel_run(cs_->get(), &im, nullptr, nullptr, &world), ROADNN_ERROR_WRONG_MODEL,
                   "runs a convnext model, not StixelNExT++");
  EXPECT_API_ERROR(roadnn_stixel_run(ds_->get(), &im, nullptr, nullptr, &world), ROADNN_ERROR_WRONG_MODEL,
                   "fasterrcnn_mobilenet_v3_large_320_fpn");
  EXPECT_TRUE(same_bits(&world, &world0, sizeof world));
  EXPECT_API_ERROR(roadnn_detect(cs_->get(), &im, &dets), ROADNN_ERROR_WRONG_MODEL, "not a Faster R-CNN");
  EXPECT_API_ERROR(roadnn_detect(ss_->get(), &im, &dets), ROADNN_ERROR_WRONG_MODEL, "stixelnext");
  EXPECT_TRUE(same_bits(&dets, &dets0, sizeof dets));
  // The kind is checked before the other arguments' contents.
  EXPECT_API_ERROR(roadnn_convnext_run(ss_->get(), x.data(), 3, y.data(), 1), ROADNN_ERROR_WRONG_MODEL, "ConvNeXt");
}

TEST_F(ApiMisuseModels, StixelRunChecksEveryArgument) {
  roadnn_session* s = ss_->get();
  const auto px = pixels(kStixelW, kStixelH, 2);
  const roadnn_image im = image_of(px, kStixelW, kStixelH);
  const roadnn_camera cam = camera_for(kStixelW, kStixelH, true);
  const roadnn_stixel_params dp = roadnn_stixel_default_params();
  roadnn_stixel_world world;
  std::memset(&world, 0x5a, sizeof world);
  const roadnn_stixel_world world0 = world;

  EXPECT_API_ERROR(roadnn_stixel_run(nullptr, &im, &cam, &dp, &world), ROADNN_ERROR_INVALID_ARGUMENT,
                   "session is null");
  EXPECT_API_ERROR(roadnn_stixel_run(s, nullptr, &cam, &dp, &world), ROADNN_ERROR_INVALID_ARGUMENT, "image is null");
  EXPECT_API_ERROR(roadnn_stixel_run(s, &im, &cam, &dp, nullptr), ROADNN_ERROR_INVALID_ARGUMENT, "out is null");
  roadnn_image bad = im;
  bad.data = nullptr;
  EXPECT_API_ERROR(roadnn_stixel_run(s, &bad, &cam, &dp, &world), ROADNN_ERROR_INVALID_ARGUMENT, "image->data is null");

  // Bad images.
  struct ImageCase {
    int w, h;
    std::size_t stride;
    const char* part;
  };
  const ImageCase images[] = {
      {0, kStixelH, 0, "image size"},    {kStixelW, 0, 0, "image size"},
      {-5, kStixelH, 0, "image size"},   {0, 0, 0, "image size"},
      {65536, 1, 0, "image size"},       {kStixelW, kStixelH, 3 * kStixelW - 1, "stride"},
      {kStixelW, kStixelH, 1, "stride"},
  };
  for (const ImageCase& c : images) {
    SCOPED_TRACE(std::to_string(c.w) + "x" + std::to_string(c.h) + " stride " + std::to_string(c.stride));
    roadnn_image b = im;
    b.width = c.w, b.height = c.h, b.stride = c.stride;
    EXPECT_API_ERROR(roadnn_stixel_run(s, &b, &cam, &dp, &world), ROADNN_ERROR_INVALID_ARGUMENT, c.part);
  }

  // Bad options.
  struct ParamCase {
    void (*change)(roadnn_stixel_params&);
    bool camera;
    const char* part;
  };
  const ParamCase cases[] = {
      {[](roadnn_stixel_params& p) { p.threshold = 2; }, true, "threshold"},
      {[](roadnn_stixel_params& p) { p.threshold = -0.01; }, true, "threshold"},
      {[](roadnn_stixel_params& p) { p.threshold = kNaN; }, true, "threshold"},
      {[](roadnn_stixel_params& p) { p.train_focal = -1; }, true, "train_focal"},
      {[](roadnn_stixel_params& p) { p.train_focal = kNaN; }, true, "train_focal"},
      {[](roadnn_stixel_params& p) { p.train_focal = std::numeric_limits<double>::infinity(); }, true, "train_focal"},
      {[](roadnn_stixel_params& p) { p.train_focal = 100; }, false, "train_focal needs a camera"},
      {[](roadnn_stixel_params& p) { p.cluster = 2; }, true, "cluster must be 0 or 1"},
      {[](roadnn_stixel_params& p) { p.cluster = 1; }, false, "clustering needs a camera"},
      {[](roadnn_stixel_params& p) { p.cluster = 1, p.cluster_eps = 0; }, true, "cluster_eps"},
      {[](roadnn_stixel_params& p) { p.cluster = 1, p.cluster_eps = kNaN; }, true, "cluster_eps"},
      {[](roadnn_stixel_params& p) { p.cluster = 1, p.cluster_min_samples = 0; }, true, "cluster_min_samples"},
      {[](roadnn_stixel_params& p) { p.cluster = 1, p.axis_a = 2; }, true, "axis_a"},
      {[](roadnn_stixel_params& p) { p.cluster = 1, p.axis_b = 3; }, true, "axis_a"},
      {[](roadnn_stixel_params& p) { p.cluster = 1, p.axis_a = -1; }, true, "axis_a"},
  };
  for (const ParamCase& c : cases) {
    SCOPED_TRACE(c.part);
    roadnn_stixel_params p = dp;
    c.change(p);
    EXPECT_API_ERROR(roadnn_stixel_run(s, &im, c.camera ? &cam : nullptr, &p, &world), ROADNN_ERROR_INVALID_ARGUMENT,
                     c.part);
  }

  // Bad cameras: not finite, singular.
  struct CameraCase {
    int index;  // into K (0..8) or T (9..24)
    double value;
    const char* part;
  };
  const CameraCase cameras[] = {
      {2, kNaN, "K[2] is not finite"},
      {0, std::numeric_limits<double>::infinity(), "K[0] is not finite"},
      {4, 1e300, "not finite"},  // finite as a double, not as the engine's float
      {9 + 3, kNaN, "T[3] is not finite"},
  };
  for (const CameraCase& c : cameras) {
    SCOPED_TRACE(c.part);
    roadnn_camera b = cam;
    if (c.index < 9)
      b.K[c.index] = c.value;
    else
      b.T[c.index - 9] = c.value;
    EXPECT_API_ERROR(roadnn_stixel_run(s, &im, &b, &dp, &world), ROADNN_ERROR_INVALID_ARGUMENT, c.part);
  }
  roadnn_camera zero = cam;
  std::memset(zero.K, 0, sizeof zero.K);
  EXPECT_API_ERROR(roadnn_stixel_run(s, &im, &zero, &dp, &world), ROADNN_ERROR_INVALID_ARGUMENT, "singular");
  zero = cam;
  std::memset(zero.T, 0, sizeof zero.T);
  EXPECT_API_ERROR(roadnn_stixel_run(s, &im, &zero, &dp, &world), ROADNN_ERROR_INVALID_ARGUMENT, "singular");
  // has_T = 0 ignores T, however bad.
  zero.has_T = 0;
  roadnn_stixel_world ok;
  EXPECT_EQ(roadnn_stixel_run(s, &im, &zero, &dp, &ok), ROADNN_OK) << roadnn_last_error();

  EXPECT_TRUE(same_bits(&world, &world0, sizeof world)) << "out written by a failing call";

  // After all that, the session still runs, and NULL params are the defaults.
  const StixelResult a = run_stixel(s, im, &cam, nullptr);
  const StixelResult b = run_stixel(s, im, &cam, &dp);
  EXPECT_TRUE(same_stixels(a, b));
  EXPECT_EQ(a.world.image_width, kStixelW);
  EXPECT_EQ(a.world.image_height, kStixelH);
  EXPECT_EQ(a.world.resized, 0);
  EXPECT_EQ(a.world.clusters, -1);
}

TEST_F(ApiMisuseModels, DetectChecksEveryArgument) {
  roadnn_session* s = ds_->get();
  const auto px = pixels(kDetW, kDetH, 3);
  const roadnn_image im = image_of(px, kDetW, kDetH);
  roadnn_detections d;
  std::memset(&d, 0x5a, sizeof d);
  const roadnn_detections d0 = d;
  EXPECT_API_ERROR(roadnn_detect(nullptr, &im, &d), ROADNN_ERROR_INVALID_ARGUMENT, "session is null");
  EXPECT_API_ERROR(roadnn_detect(s, nullptr, &d), ROADNN_ERROR_INVALID_ARGUMENT, "image is null");
  EXPECT_API_ERROR(roadnn_detect(s, &im, nullptr), ROADNN_ERROR_INVALID_ARGUMENT, "out is null");
  struct ImageCase {
    const std::uint8_t* data;
    int w, h;
    std::size_t stride;
    const char* part;
  };
  const ImageCase images[] = {
      {nullptr, kDetW, kDetH, 0, "image->data is null"},
      {px.data(), 0, kDetH, 0, "image size"},
      {px.data(), kDetW, 0, 0, "image size"},
      {px.data(), kDetW, -1, 0, "image size"},
      {px.data(), kDetW, 70000, 0, "image size"},
      {px.data(), kDetW, kDetH, 3 * kDetW - 1, "stride"},
      {px.data(), 31, 40, 0, "at least 32x32"},
      {px.data(), 40, 31, 0, "at least 32x32"},
  };
  for (const ImageCase& c : images) {
    SCOPED_TRACE(std::to_string(c.w) + "x" + std::to_string(c.h) + " stride " + std::to_string(c.stride));
    const roadnn_image b{c.data, c.w, c.h, c.stride};
    EXPECT_API_ERROR(roadnn_detect(s, &b, &d), ROADNN_ERROR_INVALID_ARGUMENT, c.part);
  }
  EXPECT_TRUE(same_bits(&d, &d0, sizeof d)) << "out written by a failing call";
  // The session still works and finds something in the synthetic image.
  const auto dets = run_detect(s, im);
  EXPECT_FALSE(dets.empty());
  for (const auto& x : dets) {
    EXPECT_GE(x.label, 1);
    EXPECT_LT(x.label, kDetClasses);
    EXPECT_GE(x.score, 0.05f);
    EXPECT_LE(x.x1, x.x2);
    EXPECT_LE(x.y1, x.y2);
  }
}

// One thread's error is not another's: a failure on A leaves B's message empty, and
// B's own failure does not replace A's.
TEST(ApiLastError, IsPerThread) {
  const roadnn_model_params p = params(ROADNN_MODEL_CONVNEXT);
  roadnn_model* m = nullptr;
  ASSERT_EQ(roadnn_model_load_file(nullptr, &p, &m), ROADNN_ERROR_INVALID_ARGUMENT);
  const std::string mine = roadnn_last_error();
  ASSERT_NE(mine.find("path is null"), std::string::npos) << mine;

  std::string seen_before, seen_after;
  roadnn_status other_status = ROADNN_OK;
  std::thread t([&] {
    seen_before = roadnn_last_error();
    other_status = roadnn_model_get_info(nullptr, nullptr);
    seen_after = roadnn_last_error();
  });
  t.join();
  EXPECT_EQ(seen_before, "") << "thread B sees thread A's error";
  EXPECT_EQ(other_status, ROADNN_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(seen_after.find("roadnn_model_get_info"), std::string::npos) << seen_after;
  EXPECT_EQ(std::string(roadnn_last_error()), mine) << "thread A's message changed by thread B";

  // Many threads failing differently at once each read their own message.
  constexpr int kThreads = 8;
  std::atomic<int> wrong{0};
  std::vector<std::thread> pool;
  for (int i = 0; i < kThreads; ++i)
    pool.emplace_back([i, &wrong] {
      for (int k = 0; k < 200; ++k) {
        const std::string path = "/nonexistent/thread_" + std::to_string(i) + "_" + std::to_string(k);
        const roadnn_model_params q = roadnn_model_default_params(ROADNN_MODEL_CONVNEXT);
        roadnn_model* out = nullptr;
        if (roadnn_model_load_file(path.c_str(), &q, &out) != ROADNN_ERROR_IO ||
            std::string(roadnn_last_error()).find(path + ":") != 0)
          ++wrong;
      }
    });
  for (auto& th : pool) th.join();
  EXPECT_EQ(wrong.load(), 0);
}

}  // namespace

// Issue 14: a V1/V3-shaped StixelNExT++ file with nothing saying which head warns
// (once, as a model warning); a declared head the tensors contradict fails to load.
TEST_F(ApiMisuseModels, StixelHeadAmbiguityAndContradiction) {
  auto specs = nn::convnext_tensor_specs(small_convnext(), "features.");
  for (auto& s : nn::stixel_head_tensor_specs(nn::StixelHeadVariant::V1, 28, "classifier.")) specs.push_back(s);
  const std::vector<std::pair<std::string, std::string>> size = {
      {"stixelnext.input_height", std::to_string(kStixelH)}, {"stixelnext.input_width", std::to_string(kStixelW)}};
  const WeightFile v13("stixel_v13.safetensors", specs, 5, size);
  ModelPtr m = load_file(v13.path, params(ROADNN_MODEL_STIXELNEXT));
  ASSERT_EQ(roadnn_model_warning_count(m.get()), 1u);
  const std::string text = roadnn_model_warning(m.get(), 0);
  EXPECT_TRUE(is_one_line(text.c_str()));
  EXPECT_NE(text.find("V1"), std::string::npos) << text;
  EXPECT_NE(text.find("V3"), std::string::npos) << text;
  roadnn_model_params p = params(ROADNN_MODEL_STIXELNEXT);
  p.stixel_head = 3;
  EXPECT_EQ(roadnn_model_warning_count(load_file(v13.path, p).get()), 0u);

  auto declared = size;
  declared.push_back({"stixelnext.head", "v4"});
  const WeightFile bad("stixel_bad_head.safetensors", specs, 5, declared);
  roadnn_model* out = nullptr;
  const roadnn_model_params sp = params(ROADNN_MODEL_STIXELNEXT);
  EXPECT_EQ(roadnn_model_load_file(bad.path.c_str(), &sp, &out), ROADNN_ERROR_BAD_MODEL);
  EXPECT_EQ(out, nullptr);
  const std::string err = roadnn_last_error();
  EXPECT_NE(err.find("stixelnext.head=v4"), std::string::npos) << err;
  EXPECT_NE(err.find("classifier.local_mixing.depthwise.weight"), std::string::npos) << err;
}
