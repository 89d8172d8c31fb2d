// Issue 16, "done means" 1: for ConvNeXt-Tiny, StixelNExT++ V4 and
// fasterrcnn_resnet50_fpn, `nnrun --dump` and `scripts/torch_dump.py` run on the same
// weights and input (the reference fixtures' files), and `nncompare` compares the two
// dumps. Each test asserts
//   (a) every program exits 0 (a missing torch fails torch_dump.py with its install hint),
//   (b) the names compared (present in both dumps) include an explicit list built from the
//       model's configuration: every stage and block, the stem and downsampling layers,
//       StixelNExT++'s avgpool and head modules, ResNet-50's layers and bottlenecks, every
//       FPN level, the RPN head's outputs per level and the RoI head's tensors; modules the
//       engine fuses count when the engine's dump.covers names them under a compared tensor,
//   (c) every compared tensor within the tolerance of that model's PyTorch tests.
// Faster R-CNN's proposals (rpn[0][0]) and everything downstream of them are compared
// row by row after matching the proposals by box (docs/NUMERICS.md: torchvision and the
// engine order near-tied proposals differently, which permutes the RoI rows).
#include <gtest/gtest.h>
#include <stdlib.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "tests/detection/match.h"
#include "tests/nncompare/nncompare_run.h"
#include "tests/reference/torch_ref.h"
#include "weights/json.h"
#include "weights/safetensors.h"

namespace {

// Tolerances of each model's PyTorch tests (max |diff| <= rtol * max |ref| + atol):
// ConvNeXt: tests/reference/test_convnext_torch.cpp kRelTol.
constexpr double kConvNeXtRtol = 3e-5;
// StixelNExT++: the prediction within 1e-5 absolute (test_stixelnext_torch.cpp kTol);
// its backbone and the head's features before the sigmoid at the ConvNeXt tolerance.
constexpr double kStixelPredictionAtol = 1e-5;
// Faster R-CNN ResNet-50: its convolutions are mostly Winograd 3x3, held to 1e-5 of
// max |ref| per op (test_ops_torch.cpp kWinogradRelTol; docs/ENGINEERING.md: "within
// 1e-5 of PyTorch per layer"); the transform within 1e-5 absolute (max |ref| ~2.4).
constexpr double kR50Rtol = 1e-5;
// The RoI head downstream of the proposals: a proposal's corners differ from
// torchvision's by up to ~3e-7 of the image size (box decoding of slightly different
// deltas), which RoIAlign's bilinear sampling of the FPN features turns into ~1.6e-5
// of max |ref| (measured); held to nncompare's default rtol, 1e-4.
constexpr double kR50RoiRtol = 1e-4;

std::string quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

// One folder per test, removed at the end (the R50 dumps are over a gigabyte).
class DumpCrossTorch : public ::testing::Test {
 protected:
  void SetUp() override {
    char tmpl[] = "/tmp/dump_cross_torch_XXXXXX";
    ASSERT_NE(mkdtemp(tmpl), nullptr);
    dir_ = tmpl;
    engine_ = dir_ + "/roadnn.dump.safetensors";
    torch_ = dir_ + "/torch.dump.safetensors";
    output_ = dir_ + "/y.safetensors";
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  // Runs `cmd` with stdout/stderr to files; returns the exit code (-1: no normal exit).
  int shell(const std::string& cmd, const std::string& tag, std::string* err) const {
    const std::string e = dir_ + "/" + tag + ".err";
    const int status = std::system((cmd + " >" + dir_ + "/" + tag + ".out 2>" + e).c_str());
    std::stringstream s;
    s << std::ifstream(e).rdbuf();
    *err = s.str();
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }

  // nnrun --dump and torch_dump.py (with --outputs: nnrun --output's names too) on the
  // same weights and input; `filter` goes to both (--dump-filter / --filter).
  void dump_both(const std::string& model, const std::string& weights, const std::string& input,
                 const std::string& filter) {
    for (const std::string& f : {weights, input})
      ASSERT_TRUE(std::ifstream(f).good())
          << f << " is missing: its PyTorch generator (ctest fixture ref_*) failed or did not run; it needs "
          << "python3-torch and python3-torchvision for /usr/bin/python3";
    std::string err;
    std::string cmd = std::string(NNRUN_PATH) + " --model " + model + " --weights " + quote(weights) + " --input " +
                      quote(input) + " --output " + quote(output_) + " --dump " + quote(engine_) + " --threads 2 --quiet";
    if (!filter.empty()) cmd += " --dump-filter " + quote(filter);
    ASSERT_EQ(shell(cmd, "nnrun", &err), 0) << cmd << "\n" << err;
    cmd = std::string(TORCH_PYTHON) + " " + ROADNN_SOURCE_DIR + "/scripts/torch_dump.py --model " + model +
          " --weights " + quote(weights) + " --input " + quote(input) + " --output " + quote(torch_) +
          " --outputs --threads 2";
    if (!filter.empty()) cmd += " --filter " + quote(filter);
    ASSERT_EQ(shell(cmd, "torch_dump", &err), 0)
        << cmd << "\n"
        << err << "(scripts/torch_dump.py needs python3-torch and python3-torchvision for " << TORCH_PYTHON
        << ": apt-get install -y python3-torch python3-torchvision python3-numpy)";
  }

  // nncompare --json A REF `args`; expects exit status `code`.
  json::Value compare(const std::string& a, const std::string& ref, const std::string& args, int code) const {
    nncompare_test::Result r = nncompare_test::run(dir_, quote(a) + " " + quote(ref) + " --json " + args);
    EXPECT_EQ(r.code, code) << "nncompare " << a << " " << ref << " " << args << "\n" << r.err;
    if (r.out.empty()) return json::Value();
    return json::parse(r.out, "nncompare --json");
  }

  std::string dir_, engine_, torch_, output_;
};

// The tensors nncompare compared (present in both files).
std::set<std::string> compared_names(const json::Value& report) {
  std::set<std::string> names;
  if (!report.is_object()) return names;
  for (const json::Value& t : report.get("tensors")->array()) {
    const std::string s = t.get("status")->str();
    if (s != "only_in_a" && s != "only_in_ref") names.insert(t.get("name")->str());
  }
  return names;
}

// Modules the engine's dump says a compared tensor stands for (dump.covers.<name>).
std::set<std::string> covered_names(const std::string& engine_dump, const std::set<std::string>& compared) {
  std::set<std::string> covered;
  const weights::SafeTensors d = weights::SafeTensors::load(engine_dump);
  for (const auto& [key, value] : d.metadata()) {
    const std::string prefix = "dump.covers.";
    if (key.compare(0, prefix.size(), prefix) != 0 || !compared.count(key.substr(prefix.size()))) continue;
    std::stringstream s(value);
    for (std::string m; std::getline(s, m, ',');) covered.insert(m);
  }
  return covered;
}

// (b): every name of `required` compared; every name of `fused` compared or covered.
void expect_coverage(const std::set<std::string>& compared, const std::set<std::string>& covered,
                     const std::vector<std::string>& required, const std::vector<std::string>& fused,
                     const std::string& what) {
  std::string missing;
  for (const std::string& n : required)
    if (!compared.count(n)) missing += " " + n;
  for (const std::string& n : fused)
    if (!compared.count(n) && !covered.count(n)) missing += " " + n + "(neither compared nor in a dump.covers)";
  EXPECT_EQ(missing, "") << what << ": names the cross-check must compare";
}

// (c): every compared tensor ok, max |diff| <= allowed; prints the worst of the report.
void expect_within(const json::Value& report, double rtol, double atol, const std::string& what) {
  ASSERT_TRUE(report.is_object()) << what << ": no nncompare report";
  EXPECT_TRUE(report.get("ok")->boolean()) << what;
  EXPECT_GT(report.get("compared")->number(), 0) << what;
  double worst = 0;
  std::string worst_name;
  for (const json::Value& t : report.get("tensors")->array()) {
    const std::string name = t.get("name")->str(), status = t.get("status")->str();
    if (status == "only_in_a" || status == "only_in_ref") continue;
    EXPECT_EQ(status, "ok") << what << ": " << name;
    const json::Value* d = t.get("max_abs_diff");
    const json::Value* m = t.get("max_abs_ref");
    ASSERT_TRUE(d && d->is_number() && m && m->is_number()) << what << ": " << name << " has a non-finite difference";
    EXPECT_LE(d->number(), atol + rtol * m->number()) << what << ": " << name;
    const double rel = m->number() > 0 ? d->number() / m->number() : d->number();
    if (rel >= worst) worst = rel, worst_name = name;
  }
  std::printf("%s: %d tensors compared, worst max|diff| / max|ref| %.3g (%s); allowed %g * max|ref| + %g\n",
              what.c_str(), static_cast<int>(report.get("compared")->number()), worst, worst_name.c_str(), rtol, atol);
}

// ConvNeXt-Tiny's features: stem, downsampling layers, stages and every block.
void convnext_tiny_names(std::vector<std::string>* required, std::vector<std::string>* fused) {
  const int depths[4] = {3, 3, 9, 3};
  required->push_back("features.0");
  for (int s = 0; s < 4; ++s) {
    const std::string stage = "features." + std::to_string(2 * s + 1);
    if (s > 0) {
      const std::string down = "features." + std::to_string(2 * s);
      required->push_back(down);
      for (const char* m : {".0", ".1"}) fused->push_back(down + m);  // LayerNorm2d, Conv2d
    }
    for (int b = 0; b < depths[s]; ++b) {
      const std::string block = stage + "." + std::to_string(b);
      required->push_back(block);
      // The permuted MLP's modules the engine fuses into the block output.
      for (const char* m : {".block", ".block.5", ".block.6", ".stochastic_depth"}) fused->push_back(block + m);
    }
    required->push_back(stage);
  }
  for (const char* m : {"features.0.0", "features.0.1"}) fused->push_back(m);
}

TEST_F(DumpCrossTorch, ConvNeXtTiny) {
  dump_both("convnext_tiny", reftest::ref_path("convnext_tiny_weights.safetensors"),
            reftest::ref_path("convnext_case_tiny_odd.safetensors"), "");
  if (HasFatalFailure()) return;
  const json::Value report = compare(engine_, torch_, "--rtol " + std::to_string(kConvNeXtRtol), 0);
  std::vector<std::string> required, fused;
  convnext_tiny_names(&required, &fused);
  const auto compared = compared_names(report);
  expect_coverage(compared, covered_names(engine_, compared), required, fused, "convnext_tiny");
  expect_within(report, kConvNeXtRtol, 0, "convnext_tiny");
  // nnrun's output file against the same dump's `features`.
  const json::Value out = compare(output_, torch_, "--rtol " + std::to_string(kConvNeXtRtol) + " --filter '^features$'", 0);
  EXPECT_EQ(compared_names(out), (std::set<std::string>{"features"}));
  expect_within(out, kConvNeXtRtol, 0, "convnext_tiny output");
}

TEST_F(DumpCrossTorch, StixelNExTV4) {
  dump_both("stixelnext", reftest::ref_path("stixel_v4_weights.safetensors"),
            reftest::ref_path("stixel_case_v4_small.safetensors"), "");
  if (HasFatalFailure()) return;
  std::vector<std::string> required, fused;
  convnext_tiny_names(&required, &fused);
  // The authors' model: features, avgpool (mean over all feature rows), the V4 head.
  for (const char* n : {"features", "avgpool", "classifier.local_mixing.depthwise", "classifier.local_mixing.pointwise",
                        "classifier.local_mixing", "classifier.shared_reduce", "classifier.up.0", "classifier.up.1",
                        "classifier.up", "classifier"})
    required.push_back(n);
  // Fused with their sigmoids and concatenation into `classifier`.
  for (const char* n : {"classifier.geometry_head", "classifier.depth_head", "classifier.probability_head"})
    fused.push_back(n);
  // Backbone and head features at ConvNeXt's tolerance, the prediction at StixelNExT's.
  const std::string rtol = std::to_string(kConvNeXtRtol), atol = std::to_string(kStixelPredictionAtol);
  const json::Value all = compare(engine_, torch_, "--rtol " + rtol, 0);
  const auto compared = compared_names(all);
  expect_coverage(compared, covered_names(engine_, compared), required, fused, "stixelnext v4");
  expect_within(all, kConvNeXtRtol, 0, "stixelnext v4");
  const json::Value head = compare(engine_, torch_, "--rtol 0 --atol " + atol + " --filter '^classifier$'", 0);
  EXPECT_EQ(compared_names(head), (std::set<std::string>{"classifier"}));
  expect_within(head, 0, kStixelPredictionAtol, "stixelnext v4 classifier");
  // nnrun's `prediction` and torch_dump.py's: the same name, the same columns rule
  // (W / 8 = 80 columns: the fixture's weights carry no stixelnext.* metadata).
  const json::Value out = compare(output_, torch_, "--rtol 0 --atol " + atol + " --filter '^prediction$'", 0);
  EXPECT_EQ(compared_names(out), (std::set<std::string>{"prediction"}));
  expect_within(out, 0, kStixelPredictionAtol, "stixelnext v4 prediction");
  const weights::SafeTensors y = weights::SafeTensors::load(output_);
  EXPECT_EQ(y.info("prediction").shape, (std::vector<std::int64_t>{1, 4, 64, 640 / 8}));
}

// Rows of a [R, ...] float tensor of two dumps, matched by `pairs` (ref row, our row):
// max |diff| over the matched rows against rtol * max |ref| of the whole tensor.
void expect_rows_within(const weights::SafeTensors& ours, const weights::SafeTensors& ref, const std::string& name,
                        const std::vector<std::pair<std::size_t, std::size_t>>& pairs, double rtol, double* worst) {
  ASSERT_TRUE(ours.has(name) && ref.has(name)) << name;
  const auto& sa = ours.info(name).shape;
  const auto& sr = ref.info(name).shape;
  ASSERT_EQ(sa.size(), sr.size()) << name;
  ASSERT_TRUE(std::equal(sa.begin() + 1, sa.end(), sr.begin() + 1)) << name << ": row shapes differ";
  const std::vector<float> a = ours.f32(name), r = ref.f32(name);
  const std::size_t row = sr[0] > 0 ? r.size() / static_cast<std::size_t>(sr[0]) : 0;
  double max_ref = 0, max_diff = 0;
  for (float v : r) max_ref = std::max(max_ref, std::fabs(static_cast<double>(v)));
  for (const auto& [i, j] : pairs)
    for (std::size_t k = 0; k < row; ++k) {
      const double d = std::fabs(static_cast<double>(a[j * row + k]) - r[i * row + k]);
      if (!(d <= max_diff)) max_diff = std::isnan(d) ? INFINITY : d;
    }
  EXPECT_LE(max_diff, rtol * max_ref) << name << " over " << pairs.size() << " matched rows, max|ref| " << max_ref;
  const double rel = max_ref > 0 ? max_diff / max_ref : max_diff;
  std::printf("  %-36s %zu matched rows: max|diff| %.4g (%.3g of max|ref| %.4g)\n", name.c_str(), pairs.size(),
              max_diff, rel, max_ref);
  *worst = std::max(*worst, rel);
}

// For each reference proposal the engine's proposal of highest IoU, if >= min_iou.
std::vector<std::pair<std::size_t, std::size_t>> pair_boxes(const std::vector<dettest::Box>& ref,
                                                            const std::vector<dettest::Box>& ours, double min_iou) {
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  for (std::size_t i = 0; i < ref.size(); ++i) {
    double best = min_iou;
    std::size_t at = ours.size();
    for (std::size_t j = 0; j < ours.size(); ++j) {
      const double v = dettest::iou(ref[i], ours[j]);
      if (v >= best) best = v, at = j;
    }
    if (at < ours.size()) pairs.emplace_back(i, at);
  }
  return pairs;
}

TEST_F(DumpCrossTorch, FasterRcnnResNet50Fpn) {
  // torchvision resizes the 457x613 image to 800x1088: only the boundaries the
  // coverage needs are written (no per-conv internals): about 0.6 GB per side.
  const std::string filter =
      "^(transform|backbone\\.body\\.layer[1-4](\\.[0-9]+)?$|backbone\\.fpn\\[|rpn\\.head\\[|rpn\\[0\\]\\[0\\]$|"
      "roi_heads\\.box_(roi_pool|head|predictor)|roi_heads\\[)";
  dump_both("fasterrcnn_resnet50_fpn", reftest::ref_path("det_r50_weights.safetensors"),
            reftest::ref_path("det_r50_odd.safetensors"), filter);
  if (HasFatalFailure()) return;

  // Everything up to and including the RPN head's outputs: nncompare at the tolerance.
  const std::string rtol = std::to_string(kR50Rtol);
  const std::string upstream = "'^(transform|backbone\\.|rpn\\.head)'";
  const json::Value report = compare(engine_, torch_, "--rtol " + rtol + " --filter " + upstream, 0);
  expect_within(report, kR50Rtol, 0, "fasterrcnn_resnet50_fpn up to the RPN head");

  // Coverage, from torchvision's resnet50 (bottlenecks 3, 4, 6, 3), its FPN (4 levels +
  // pool), RPNHead (objectness and box deltas per level) and the RoI heads.
  std::vector<std::string> required = {"transform[0]"}, fused;
  const int blocks[4] = {3, 4, 6, 3};
  for (int l = 1; l <= 4; ++l) {
    const std::string layer = "backbone.body.layer" + std::to_string(l);
    for (int i = 0; i < blocks[l - 1]; ++i) required.push_back(layer + "." + std::to_string(i));
    required.push_back(layer);
  }
  for (const char* level : {"0", "1", "2", "3", "pool"}) required.push_back(std::string("backbone.fpn[") + level + "]");
  for (int out = 0; out < 2; ++out)
    for (int level = 0; level < 5; ++level)
      required.push_back("rpn.head[" + std::to_string(out) + "][" + std::to_string(level) + "]");
  const std::vector<std::string> roi = {"roi_heads.box_roi_pool",          "roi_heads.box_head",
                                        "roi_heads.box_predictor.cls_score", "roi_heads.box_predictor.bbox_pred",
                                        "roi_heads.box_predictor[0]",        "roi_heads.box_predictor[1]"};
  required.push_back("rpn[0][0]");
  required.insert(required.end(), roi.begin(), roi.end());
  fused = {"roi_heads.box_head.fc6", "roi_heads.box_head.fc7"};

  const weights::SafeTensors ours = weights::SafeTensors::load(engine_), ref = weights::SafeTensors::load(torch_);
  std::set<std::string> compared;
  for (const std::string& n : ours.names())
    if (ref.has(n)) compared.insert(n);
  expect_coverage(compared, covered_names(engine_, compared), required, fused, "fasterrcnn_resnet50_fpn");

  // The proposals and the RoI head: rows matched by proposal box (IoU >= 0.99 both ways,
  // as the detector tests match), >= 95 % of them; matched proposals within kR50Rtol,
  // matched RoI-head rows within kR50RoiRtol.
  const auto ob = dettest::to_boxes(ours.f32("rpn[0][0]")), rb = dettest::to_boxes(ref.f32("rpn[0][0]"));
  ASSERT_GE(rb.size(), 100u) << "the reference should exercise real proposals";
  const auto a = dettest::match(rb, {}, {}, ob, {}, {}, 0.99, 0);
  const auto b = dettest::match(ob, {}, {}, rb, {}, {}, 0.99, 0);
  EXPECT_GE(a.fraction(), 0.95) << "torchvision proposals unmatched:" << a.unmatched;
  EXPECT_GE(b.fraction(), 0.95) << "our proposals unmatched:" << b.unmatched;
  const auto pairs = pair_boxes(rb, ob, 0.99);
  std::size_t same_row = 0;
  for (const auto& [i, j] : pairs) same_row += i == j;
  std::printf("fasterrcnn_resnet50_fpn proposals: torch %zu, ours %zu, matched %zu (%zu in the same row)\n", rb.size(),
              ob.size(), pairs.size(), same_row);
  double worst = 0;
  expect_rows_within(ours, ref, "rpn[0][0]", pairs, kR50Rtol, &worst);
  for (const std::string& n : roi) expect_rows_within(ours, ref, n, pairs, kR50RoiRtol, &worst);
  std::printf("fasterrcnn_resnet50_fpn proposals and RoI head: worst max|diff| / max|ref| %.3g over matched rows\n",
              worst);

  // The detections of nnrun's output file against torchvision's, as the detector tests:
  // >= 95 % matched both ways at IoU >= 0.99, score within 1e-3, same label.
  const weights::SafeTensors y = weights::SafeTensors::load(output_);
  const auto yb = dettest::to_boxes(y.f32("boxes")), tb = dettest::to_boxes(ref.f32("boxes"));
  const auto ys = y.f32("scores"), ts = ref.f32("scores");
  const auto yl = y.i64("labels"), tl = ref.i64("labels");
  ASSERT_GT(tb.size(), 10u) << "the reference should exercise real detections";
  const auto d1 = dettest::match(tb, ts, tl, yb, ys, yl, 0.99, 1e-3);
  const auto d2 = dettest::match(yb, ys, yl, tb, ts, tl, 0.99, 1e-3);
  std::printf("fasterrcnn_resnet50_fpn detections: torch %zu, ours %zu, matched %.4f / %.4f\n", tb.size(), yb.size(),
              d1.fraction(), d2.fraction());
  EXPECT_GE(d1.fraction(), 0.95) << "torchvision detections unmatched:" << d1.unmatched;
  EXPECT_GE(d2.fraction(), 0.95) << "our detections unmatched:" << d2.unmatched;
}

}  // namespace
