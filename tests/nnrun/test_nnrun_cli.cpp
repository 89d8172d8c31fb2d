// nnrun as users drive it: every malformed input gives a one-line error naming the
// file and the problem, exit code 1, and leaves no output file behind.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "nn/gemm_bf16.h"
#include "nn/layout.h"
#include "nn/models/convnext.h"
#include "apps/common/image_io.h"
#include "nn/models/detection/detectron2_faster_rcnn.h"
#include "nn/models/detection/faster_rcnn.h"
#include "nn/models/synthetic_weights.h"
#include "nn/threads.h"
#include "nn/winograd.h"
#include "weights/safetensors.h"

namespace {

// A small ConvNeXt (odd widths) so the tests are quick.
nn::ConvNeXtConfig small_config() { return {{8, 12, 20, 28}, {1, 1, 2, 1}}; }

struct Result {
  int code = -1;
  std::string err, out;
};

class NnrunCli : public testing::Test {
 protected:
  void SetUp() override {
    char tmpl[] = "/tmp/nnrun_test_XXXXXX";
    ASSERT_NE(mkdtemp(tmpl), nullptr);
    dir_ = tmpl;
    good_weights_ = nn::synthetic_weights(nn::convnext_tensor_specs(small_config(), "features."), 3).bytes();
    write("w.safetensors", good_weights_);
    write_input("x.safetensors", {1, 3, 64, 96});
  }
  void TearDown() override { std::system(("rm -rf " + dir_).c_str()); }

  std::string path(const std::string& f) const { return dir_ + "/" + f; }
  void write(const std::string& f, const std::vector<std::uint8_t>& bytes) {
    std::ofstream(path(f), std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()), bytes.size());
  }
  void write_input(const std::string& f, std::vector<std::int64_t> shape, float fill = 0.5f) {
    std::size_t n = 1;
    for (auto d : shape) n *= static_cast<std::size_t>(d);
    std::vector<float> v(n, fill);
    weights::Writer w;
    w.add_f32("input", shape, v.data());
    w.write(path(f));
  }
  Result run(const std::string& weights, const std::string& input, const std::string& extra = "",
             const std::string& model = "convnext") {
    const std::string cmd = std::string(NNRUN_PATH) + " --model " + model + " --weights " + path(weights) + " --input " +
                            path(input) + " --output " + path("y.safetensors") + " --threads 2 " + extra +
                            " >" + path("stdout") + " 2>" + path("stderr");
    Result r;
    int status = std::system(cmd.c_str());
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    std::stringstream e, o;
    e << std::ifstream(path("stderr")).rdbuf();
    o << std::ifstream(path("stdout")).rdbuf();
    r.err = e.str();
    r.out = o.str();
    return r;
  }
  bool output_exists() const { return std::ifstream(path("y.safetensors")).good(); }

  // Runs with bad weights and checks the error contract.
  void expect_weights_error(const std::vector<std::uint8_t>& bytes, const std::string& problem) {
    write("bad.safetensors", bytes);
    Result r = run("bad.safetensors", "x.safetensors");
    EXPECT_EQ(r.code, 1) << r.err;
    EXPECT_NE(r.err.find(path("bad.safetensors")), std::string::npos) << "error must name the file: " << r.err;
    EXPECT_NE(r.err.find(problem), std::string::npos) << "expected '" << problem << "' in: " << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << "one line: " << r.err;
    EXPECT_FALSE(output_exists());
  }

  // A small detector's random weights (det.safetensors) and a 90x130 image
  // (img.safetensors) for it; returns the image.
  static constexpr auto kDetector = nn::detection::FasterRcnnVariant::MobileNetV3Large320Fpn;
  static constexpr int kDetH = 90, kDetW = 130;
  std::vector<float> write_detector_case() {
    namespace det = nn::detection;
    write("det.safetensors", nn::synthetic_weights(det::faster_rcnn_tensor_specs(kDetector, 3), 4).bytes());
    std::vector<float> x(3 * kDetH * kDetW);
    for (std::size_t i = 0; i < x.size(); ++i) x[i] = static_cast<float>((i * 2654435761u) % 1000) / 999.0f;
    weights::Writer in;
    in.add_f32("input", {1, 3, kDetH, kDetW}, x.data());
    in.write(path("img.safetensors"));
    return x;
  }

  // nnrun's detections file holds exactly the library's detections.
  static void expect_same_detections(const weights::SafeTensors& y, const nn::detection::Detections& d) {
    ASSERT_EQ(y.info("boxes").shape, (std::vector<std::int64_t>{static_cast<std::int64_t>(d.boxes.size()), 4}));
    EXPECT_EQ(0, std::memcmp(y.f32("boxes").data(), d.boxes.data(), d.boxes.size() * sizeof(nn::detection::Box)));
    EXPECT_EQ(y.f32("scores"), d.scores);
    EXPECT_EQ(y.i64("labels"), d.labels);
  }

  // The header JSON of the good weights file, for targeted edits.
  std::string header() const {
    std::uint64_t n = 0;
    std::memcpy(&n, good_weights_.data(), 8);
    return std::string(good_weights_.begin() + 8, good_weights_.begin() + 8 + n);
  }
  std::vector<std::uint8_t> with_header(const std::string& h) const {
    std::uint64_t n0 = 0;
    std::memcpy(&n0, good_weights_.data(), 8);
    std::vector<std::uint8_t> out;
    out.reserve(8 + h.size() + good_weights_.size());
    for (int i = 0; i < 8; ++i) out.push_back(static_cast<std::uint8_t>(static_cast<std::uint64_t>(h.size()) >> (8 * i)));
    out.insert(out.end(), h.begin(), h.end());
    out.insert(out.end(), good_weights_.begin() + 8 + n0, good_weights_.end());
    return out;
  }
  // Replaces the first occurrence of `from` in the header (keeping its length).
  std::vector<std::uint8_t> edit_header(const std::string& from, const std::string& to) const {
    std::string h = header();
    auto pos = h.find(from);
    EXPECT_NE(pos, std::string::npos) << from;
    h.replace(pos, from.size(), to);
    return with_header(h);
  }

  std::string dir_;
  std::vector<std::uint8_t> good_weights_;
};

TEST_F(NnrunCli, RunsAndWritesFeaturesWithTiming) {
  Result r = run("w.safetensors", "x.safetensors", "--repeat 2 --profile");
  ASSERT_EQ(r.code, 0) << r.err;
  auto y = weights::SafeTensors::load(path("y.safetensors"));
  EXPECT_EQ(y.info("features").shape, (std::vector<std::int64_t>{1, 28, 2, 3}));
  for (float v : y.f32("features")) EXPECT_TRUE(std::isfinite(v));
  // The last line is the timing summary; the profile table names the layers.
  const std::string last = r.out.substr(r.out.rfind("forward_ms"));
  EXPECT_EQ(last.rfind("forward_ms min=", 0), 0u) << r.out;
  EXPECT_NE(r.out.find("features.5.1"), std::string::npos) << r.out;
}

TEST_F(NnrunCli, SameOutputForOneAndTwoThreads) {
  ASSERT_EQ(run("w.safetensors", "x.safetensors", "--threads 1").code, 0);
  auto a = weights::SafeTensors::load(path("y.safetensors")).f32("features");
  ASSERT_EQ(run("w.safetensors", "x.safetensors").code, 0);
  auto b = weights::SafeTensors::load(path("y.safetensors")).f32("features");
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * sizeof(float)));
}

// A plain ConvNeXt run goes through the public API (roadnn.hpp), a profiled one
// through the engine's runner: both say which, and give the same bits, also with
// the kernels capped (--isa, a model option on the API side).
TEST_F(NnrunCli, PlainRunsGoThroughTheApiWithTheEnginesBits) {
  for (const std::string isa : {"", "--isa scalar"}) {
    Result api = run("w.safetensors", "x.safetensors", isa);
    ASSERT_EQ(api.code, 0) << api.err;
    EXPECT_NE(api.err.find("(through the API)"), std::string::npos) << api.err;
    auto a = weights::SafeTensors::load(path("y.safetensors")).f32("features");
    Result engine = run("w.safetensors", "x.safetensors", isa + " --profile");
    ASSERT_EQ(engine.code, 0) << engine.err;
    EXPECT_EQ(engine.err.find("(through the API)"), std::string::npos) << engine.err;
    auto b = weights::SafeTensors::load(path("y.safetensors")).f32("features");
    ASSERT_EQ(a.size(), b.size());
    EXPECT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * sizeof(float))) << isa;
  }
}

// --precision bf16 is the library's bf16 model, bitwise, and says so on stderr.
TEST_F(NnrunCli, PrecisionBf16IsTheLibrarysBf16Model) {
  if (!nn::bf16_gemm_available()) GTEST_SKIP() << "this CPU has no AVX512_BF16";
  Result r = run("w.safetensors", "x.safetensors", "--precision bf16");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("bf16"), std::string::npos) << r.err;
  auto y = weights::SafeTensors::load(path("y.safetensors")).f32("features");
  auto w = weights::SafeTensors::load(path("w.safetensors"));
  nn::set_num_threads(2);
  nn::ConvNeXt model(w, "features.", nn::Precision::Bf16);
  model.plan(1, 64, 96);
  std::vector<float> x(3 * 64 * 96, 0.5f);
  nn::ConstTensorView v = model.forward(x.data());
  nn::set_num_threads(0);
  std::vector<float> nchw(v.count());
  nn::nhwc_to_nchw(v.data, v.shape.n, v.shape.c, v.shape.h, v.shape.w, nchw.data());
  ASSERT_EQ(y.size(), nchw.size());
  EXPECT_EQ(0, std::memcmp(y.data(), nchw.data(), y.size() * sizeof(float)));
  ASSERT_EQ(run("w.safetensors", "x.safetensors").code, 0);
  auto f32 = weights::SafeTensors::load(path("y.safetensors")).f32("features");
  EXPECT_NE(0, std::memcmp(y.data(), f32.data(), y.size() * sizeof(float))) << "bf16 gave f32's bits";
}

// Usage errors (exit 2, the problem on the first line, no output): an unknown precision, bf16 for a detector,
// bf16 with the kernels forced below AVX-512.
TEST_F(NnrunCli, PrecisionUsageErrors) {
  for (const auto& [extra, model, problem] : std::vector<std::tuple<std::string, std::string, std::string>>{
           {"--precision fp8", "convnext", "--precision must be f32 or bf16"},
           {"--precision bf16 --isa avx2", "convnext", "needs AVX512_BF16"},
           {"--precision bf16", "fasterrcnn_resnet50_fpn", "runs in f32 only"}}) {
    if (problem == "runs in f32 only" && !nn::bf16_gemm_available()) continue;  // fails earlier, differently
    Result r = run("w.safetensors", "x.safetensors", extra, model);
    EXPECT_EQ(r.code, 2) << extra << ": " << r.err;
    EXPECT_NE(r.err.find(problem), std::string::npos) << extra << ": " << r.err;
    EXPECT_EQ(r.err.rfind("nnrun: ", 0), 0u) << r.err;
    EXPECT_FALSE(output_exists()) << extra;
  }
}

TEST_F(NnrunCli, TruncatedFile) {
  expect_weights_error({good_weights_.begin(), good_weights_.begin() + 5}, "");
  expect_weights_error({good_weights_.begin(), good_weights_.end() - 100}, "");
}

TEST_F(NnrunCli, HeaderLengthPastTheEnd) {
  auto bytes = good_weights_;
  std::uint64_t n = bytes.size() + 10;
  std::memcpy(bytes.data(), &n, 8);
  expect_weights_error(bytes, "header length");
}

TEST_F(NnrunCli, InvalidJson) {
  std::string h = header();
  h[h.size() / 2] = '#';
  expect_weights_error(with_header(h), "");
}

TEST_F(NnrunCli, DuplicateKey) {
  std::string h = header();
  // Repeat the first member: {"a":...,  ->  {"a":...,"a":...,
  const auto end_first = h.find("},") + 2;
  h = "{" + h.substr(1, end_first - 1) + h.substr(1);
  expect_weights_error(with_header(h), "duplicate");
}

TEST_F(NnrunCli, UnknownDtype) { expect_weights_error(edit_header("\"F32\"", "\"X32\""), "dtype"); }

TEST_F(NnrunCli, OverlappingOrGappedOffsets) {
  // Shifting one tensor's start makes it overlap its predecessor or leave a gap.
  std::string h = header();
  auto pos = h.find("\"data_offsets\":[", h.find("features.0.0.bias"));
  ASSERT_NE(pos, std::string::npos);
  pos += 16;
  auto comma = h.find(',', pos);
  std::uint64_t begin = std::stoull(h.substr(pos, comma - pos));
  std::string down = h, up = h;
  down.replace(pos, comma - pos, std::to_string(begin - 4));
  up.replace(pos, comma - pos, std::to_string(begin + 4));
  expect_weights_error(with_header(down), "");
  expect_weights_error(with_header(up), "");
}

TEST_F(NnrunCli, MissingTensor) {
  auto specs = nn::convnext_tensor_specs(small_config(), "features.");
  auto it = std::find_if(specs.begin(), specs.end(), [](auto& s) { return s.name == "features.3.0.block.3.weight"; });
  specs.erase(it);
  expect_weights_error(nn::synthetic_weights(specs, 3).bytes(), "features.3.0.block.3.weight");
}

TEST_F(NnrunCli, WrongShape) {
  auto specs = nn::convnext_tensor_specs(small_config(), "features.");
  for (auto& s : specs)
    if (s.name == "features.1.0.block.0.weight") s.shape = {8, 1, 5, 5};
  expect_weights_error(nn::synthetic_weights(specs, 3).bytes(), "features.1.0.block.0.weight");
}

TEST_F(NnrunCli, NanOrInfInAWeight) {
  for (float bad : {NAN, INFINITY}) {
    auto specs = nn::convnext_tensor_specs(small_config(), "features.");
    weights::Writer w;
    nn::SplitMix64 rng(1);
    for (const auto& s : specs) {
      auto v = nn::synthetic_tensor(s, specs, rng);
      if (s.name == "features.5.1.block.5.bias") v[3] = bad;
      w.add_f32(s.name, s.shape, v.data());
    }
    expect_weights_error(w.bytes(), "features.5.1.block.5.bias");
  }
}

void expect_input_error(NnrunCli* t, const Result& r, const std::string& file, const std::string& problem) {
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find(file), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(problem), std::string::npos) << "expected '" << problem << "' in: " << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  (void)t;
}

TEST_F(NnrunCli, InputOfWrongRank) {
  write_input("bad.safetensors", {3, 64, 96});
  Result r = run("w.safetensors", "bad.safetensors");
  expect_input_error(this, r, path("bad.safetensors"), "rank");
  EXPECT_FALSE(output_exists());
}

TEST_F(NnrunCli, InputWithWrongChannelCount) {
  write_input("bad.safetensors", {1, 4, 64, 96});
  Result r = run("w.safetensors", "bad.safetensors");
  expect_input_error(this, r, path("bad.safetensors"), "channels");
  EXPECT_FALSE(output_exists());
}

TEST_F(NnrunCli, InputSmallerThan32x32) {
  write_input("bad.safetensors", {1, 3, 31, 96});
  Result r = run("w.safetensors", "bad.safetensors");
  expect_input_error(this, r, path("bad.safetensors"), "32x32");
  EXPECT_FALSE(output_exists());
}

// Issue 12, row 10: NaN/Inf in the input used to give an all-NaN output and exit 0.
TEST_F(NnrunCli, NanOrInfInTheInputIsRefused) {
  for (float bad : {NAN, -INFINITY}) {
    write_input("bad.safetensors", {1, 3, 64, 96}, bad);
    Result r = run("w.safetensors", "bad.safetensors");
    expect_input_error(this, r, path("bad.safetensors"), std::isnan(bad) ? "'input' contains NaN (element 0)"
                                                                          : "'input' contains Inf (element 0)");
    EXPECT_FALSE(output_exists());
  }
}

TEST_F(NnrunCli, MissingInputFileAndUsageErrors) {
  Result r = run("w.safetensors", "nope.safetensors");
  expect_input_error(this, r, path("nope.safetensors"), "");
  EXPECT_FALSE(output_exists());
  r = run("w.safetensors", "x.safetensors", "--repeat -1");
  EXPECT_EQ(r.code, 2) << r.err;
}

TEST_F(NnrunCli, WrongNamedModelIsRefused) {
  const std::string cmd = std::string(NNRUN_PATH) + " --model convnext_tiny --weights " + path("w.safetensors") +
                          " --input " + path("x.safetensors") + " --output " + path("y.safetensors") + " 2>" +
                          path("stderr");
  int status = std::system(cmd.c_str());
  EXPECT_EQ(WEXITSTATUS(status), 1);
  std::stringstream e;
  e << std::ifstream(path("stderr")).rdbuf();
  EXPECT_NE(e.str().find("not convnext_tiny"), std::string::npos) << e.str();
  EXPECT_FALSE(output_exists());
}

TEST_F(NnrunCli, UnusedTensorsAreListed) {
  auto specs = nn::convnext_tensor_specs(small_config(), "features.");
  specs.push_back({"classifier.2.weight", {10, 28}});
  write("extra.safetensors", nn::synthetic_weights(specs, 3).bytes());
  Result r = run("extra.safetensors", "x.safetensors");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("classifier.2.weight"), std::string::npos) << r.err;
}

TEST_F(NnrunCli, HelpListsModels) {
  const std::string cmd = std::string(NNRUN_PATH) + " --help >" + path("stdout");
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  std::stringstream o;
  o << std::ifstream(path("stdout")).rdbuf();
  EXPECT_NE(o.str().find("convnext_tiny"), std::string::npos);
  EXPECT_NE(o.str().find("--repeat"), std::string::npos);
}

// The detector's outputs and, with --dump-proposals, its RPN proposals: exactly what
// the library computes for the same weights and image.
TEST_F(NnrunCli, DetectorWritesDetectionsAndProposals) {
  namespace det = nn::detection;
  const auto v = kDetector;
  const int h = kDetH, w = kDetW;
  const std::vector<float> x = write_detector_case();

  Result r = run("det.safetensors", "img.safetensors", "--dump-proposals", det::faster_rcnn_name(v));
  ASSERT_EQ(r.code, 0) << r.err;
  auto y = weights::SafeTensors::load(path("y.safetensors"));

  auto st = weights::SafeTensors::load(path("det.safetensors"));
  det::FasterRcnn model(st, v);
  model.plan(h, w);
  const det::Detections d = model.forward(x.data());
  const auto& p = model.proposals();
  ASSERT_GT(p.boxes.size(), 0u);
  ASSERT_EQ(y.info("proposals").shape, (std::vector<std::int64_t>{static_cast<std::int64_t>(p.boxes.size()), 4}));
  EXPECT_EQ(0, std::memcmp(y.f32("proposals").data(), p.boxes.data(), p.boxes.size() * sizeof(det::Box)));
  EXPECT_EQ(y.f32("proposal_scores"), p.scores);
  EXPECT_EQ(y.i64("proposal_image_size"), (std::vector<std::int64_t>{model.sizes().resized_h, model.sizes().resized_w}));
  expect_same_detections(y, d);

  // Without the flag there are no proposals; a model without an RPN refuses the flag.
  ASSERT_EQ(run("det.safetensors", "img.safetensors", "", det::faster_rcnn_name(v)).code, 0);
  EXPECT_FALSE(weights::SafeTensors::load(path("y.safetensors")).has("proposals"));
  std::remove(path("y.safetensors").c_str());
  r = run("w.safetensors", "x.safetensors", "--dump-proposals");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("--dump-proposals"), std::string::npos) << r.err;
  EXPECT_FALSE(output_exists());
}

// --conv3x3 direct runs the model the library packs with set_winograd(false), bit for
// bit; an unknown algorithm is a usage error.
TEST_F(NnrunCli, Conv3x3DirectIsTheLibrarysDirectModel) {
  namespace det = nn::detection;
  const auto v = kDetector;
  const int h = kDetH, w = kDetW;
  const std::vector<float> x = write_detector_case();

  Result r = run("det.safetensors", "img.safetensors", "--conv3x3 direct", det::faster_rcnn_name(v));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("3x3 convolutions direct"), std::string::npos) << r.err;
  auto y = weights::SafeTensors::load(path("y.safetensors"));
  const bool saved = nn::winograd_enabled();
  nn::set_winograd(false);
  det::FasterRcnn model(weights::SafeTensors::load(path("det.safetensors")), v);
  nn::set_winograd(saved);
  model.plan(h, w);
  const det::Detections d = model.forward(x.data());
  ASSERT_GT(d.boxes.size(), 0u);
  expect_same_detections(y, d);
  std::remove(path("y.safetensors").c_str());

  r = run("det.safetensors", "img.safetensors", "--conv3x3 fft", det::faster_rcnn_name(v));
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("--conv3x3 must be winograd or direct"), std::string::npos) << r.err;
  EXPECT_FALSE(output_exists());
}

}  // namespace

// Issue 12, finding 11: an empty path is a usage error naming the options, not
// "nnrun: : cannot rename ...".
TEST_F(NnrunCli, EmptyOutputPathIsAUsageError) {
  const std::string cmd = std::string(NNRUN_PATH) + " --model convnext --weights " + path("w.safetensors") +
                          " --input " + path("x.safetensors") + " --output '' >" + path("stdout") + " 2>" +
                          path("stderr");
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 2);
  std::stringstream e;
  e << std::ifstream(path("stderr")).rdbuf();
  EXPECT_NE(e.str().find("must not be empty"), std::string::npos) << e.str();
}

// Issue 12 item 5, finding 6: an --output that is the --input or the --weights, under
// any spelling or through a symlink, is refused in one line before anything is
// written; the file keeps its bytes and no other file appears.
TEST_F(NnrunCli, OutputThatIsAnInputIsRefused) {
  ASSERT_EQ(::symlink(path("x.safetensors").c_str(), path("link.safetensors").c_str()), 0);
  auto bytes_of = [&](const std::string& f) {
    std::stringstream s;
    s << std::ifstream(path(f), std::ios::binary).rdbuf();
    return s.str();
  };
  auto entries = [&] {
    std::vector<std::string> names;
    for (const auto& e : std::filesystem::directory_iterator(dir_))
      if (e.path().filename() != "stdout" && e.path().filename() != "stderr") names.push_back(e.path().filename());
    std::sort(names.begin(), names.end());
    return names;
  };
  const std::string x_before = bytes_of("x.safetensors"), w_before = bytes_of("w.safetensors");
  const std::vector<std::string> before = entries();
  struct Case {
    std::string output, role, input;
  };
  for (const Case& c : std::vector<Case>{{path("x.safetensors"), "input", path("x.safetensors")},
                                         {dir_ + "/./w.safetensors", "weights", path("w.safetensors")},
                                         {dir_ + "/nowhere/../x.safetensors", "input", path("x.safetensors")},
                                         {path("link.safetensors"), "input", path("x.safetensors")}}) {
    const std::string cmd = std::string(NNRUN_PATH) + " --model convnext --weights " + path("w.safetensors") +
                            " --input " + path("x.safetensors") + " --output " + c.output + " >" + path("stdout") +
                            " 2>" + path("stderr");
    const int status = std::system(cmd.c_str());
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 1);
    EXPECT_EQ(bytes_of("stderr"), "nnrun: output " + c.output + " would overwrite the " + c.role + " " + c.input + "\n");
    EXPECT_EQ(bytes_of("x.safetensors"), x_before);
    EXPECT_EQ(bytes_of("w.safetensors"), w_before);
    EXPECT_EQ(entries(), before) << c.output;
  }
  EXPECT_TRUE(std::filesystem::is_symlink(path("link.safetensors")));
}

// detectron2's detector takes an RGB8 image: --image FILE and an input file's U8
// [H, W, 3] tensor give the same outputs (boxes, scores, 0-based classes, proposals
// with their logits); other input forms are one clear error.
namespace {

TEST_F(NnrunCli, Detectron2TakesAnImageOrAnRgb8Tensor) {
  namespace det = nn::detection;
  write("d2.safetensors", nn::synthetic_weights(det::detectron2_faster_rcnn_tensor_specs(2), 4).bytes());
  const int h = 60, w = 90;
  std::vector<std::uint8_t> rgb(static_cast<std::size_t>(h) * w * 3);
  for (std::size_t i = 0; i < rgb.size(); ++i) rgb[i] = static_cast<std::uint8_t>((i * 2654435761u) >> 13);
  write("img.png", imageio::encode_png(rgb.data(), w, h, 3));
  weights::Writer in;
  in.add("input", weights::DType::U8, {h, w, 3}, rgb.data());
  in.write(path("rgb.safetensors"));

  const std::string model = det::kDetectron2FasterRcnnName;
  Result r = run("d2.safetensors", "rgb.safetensors", "--dump-proposals", model);
  ASSERT_EQ(r.code, 0) << r.err;
  const auto from_tensor = weights::SafeTensors::load(path("y.safetensors"));
  ASSERT_TRUE(from_tensor.has("classes") && from_tensor.has("proposal_logits"));
  EXPECT_FALSE(from_tensor.has("labels"));
  const auto& kshape = from_tensor.info("boxes").shape;
  ASSERT_EQ(kshape.size(), 2u);
  EXPECT_EQ(from_tensor.info("classes").shape, (std::vector<std::int64_t>{kshape[0]}));
  for (auto c : from_tensor.i64("classes")) EXPECT_TRUE(c == 0 || c == 1) << c;

  const std::string cmd = std::string(NNRUN_PATH) + " --model " + model + " --weights " + path("d2.safetensors") +
                          " --image " + path("img.png") + " --output " + path("z.safetensors") +
                          " --dump-proposals --quiet 2>" + path("stderr");
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  const auto from_image = weights::SafeTensors::load(path("z.safetensors"));
  for (const char* name : {"boxes", "scores", "proposals", "proposal_logits"})
    EXPECT_EQ(from_image.f32(name), from_tensor.f32(name)) << name;
  EXPECT_EQ(from_image.i64("classes"), from_tensor.i64("classes"));
  std::remove(path("y.safetensors").c_str());

  // A float [1,3,H,W] tensor (the torchvision detectors' input) is refused by name.
  write_input("f.safetensors", {1, 3, h, w});
  r = run("d2.safetensors", "f.safetensors", "", model);
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find("expected U8 [H, W, 3]"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(path("f.safetensors")), std::string::npos) << r.err;
  EXPECT_FALSE(output_exists());
  // --image for a model without image input, and --input with --image, are usage errors.
  r = run("w.safetensors", "x.safetensors", "--image " + path("img.png"));
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("one of --input FILE and --image FILE"), std::string::npos) << r.err;
  EXPECT_FALSE(output_exists());
}

}  // namespace
