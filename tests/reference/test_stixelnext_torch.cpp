// StixelNExT++ (backbone + every head variant) against a PyTorch implementation of
// the reference specification (stixel_head_ref.py). The prediction is a sigmoid
// output, compared with an absolute tolerance of 1e-5.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <map>

#include "nn/error.h"
#include "nn/models/stixelnext.h"
#include "nn/threads.h"
#include "tests/reference/torch_ref.h"

namespace {

constexpr double kTol = 1e-5;

// The "small" case's input H x W and columns U (stixel_head_ref.py): 256x640, U = 80; in
// the small-size run (ROADNN_TEST_SIZES=small, under emulation) 64x160, U = 20.
struct SmallSize {
  int h, w, u;
};
SmallSize small_size() { return reftest::small_sizes_only() ? SmallSize{64, 160, 20} : SmallSize{256, 640, 80}; }

void check(const std::string& variant, const std::string& size, nn::StixelHeadVariant expect,
           std::optional<nn::StixelHeadVariant> force = std::nullopt) {
  if (size != "small") {
    ROADNN_SKIP_LARGE_INPUT();
  }
  weights::SafeTensors w = reftest::load_ref("stixel_" + variant + "_weights.safetensors");
  weights::SafeTensors c = reftest::load_ref("stixel_case_" + variant + "_" + size + ".safetensors");
  nn::StixelNExT model(w, force);
  EXPECT_EQ(model.head().variant(), expect);
  const auto& xs = c.info("input").shape;
  const auto& es = c.info("expected").shape;
  model.plan(static_cast<int>(xs[0]), static_cast<int>(xs[2]), static_cast<int>(xs[3]), static_cast<int>(es[3]));
  ASSERT_EQ(model.prediction_shape(), es);
  const auto x = c.f32("input");
  const float* y = model.forward(x.data());
  reftest::expect_close_abs(y, c.f32("expected"), kTol, variant + " " + size);
}

using V = nn::StixelHeadVariant;

TEST(StixelNExTTorch, V4Small) { check("v4", "small", V::V4); }
TEST(StixelNExTTorch, V1LocalAttentionSmall) { check("v1", "small", V::V1); }
TEST(StixelNExTTorch, V3GlobalAttentionSmall) { check("v3", "small", V::V3, V::V3); }
TEST(StixelNExTTorch, V2UnusedAttentionSmall) { check("v2", "small", V::V2); }
TEST(StixelNExTTorch, V0PlainSmall) { check("v0", "small", V::V0); }
TEST(StixelNExTTorch, V4FullHd) { check("v4", "fullhd", V::V4); }
TEST(StixelNExTTorch, V1FullHd) { check("v1", "fullhd", V::V1); }
TEST(StixelNExTTorch, V3FullHd) { check("v3", "fullhd", V::V3, V::V3); }
TEST(StixelNExTTorch, V0FullHd) { check("v0", "fullhd", V::V0); }

// V1 and V3 share their tensors: detection says V1, and forcing V3 changes the result.
TEST(StixelNExTTorch, V1AndV3DifferOnlyByTheForcedVariant) {
  weights::SafeTensors w = reftest::load_ref("stixel_v1_weights.safetensors");
  weights::SafeTensors c = reftest::load_ref("stixel_case_v1_small.safetensors");
  nn::StixelNExT local(w), global(w, V::V3);
  const auto x = c.f32("input");
  local.plan(1, small_size().h, small_size().w, small_size().u);
  global.plan(1, small_size().h, small_size().w, small_size().u);
  const std::size_t n = 3 * 64 * static_cast<std::size_t>(small_size().u);
  std::vector<float> a(local.forward(x.data()), local.forward(x.data()) + n);
  const float* b = global.forward(x.data());
  EXPECT_NE(0, std::memcmp(a.data(), b, n * sizeof(float)));
}

TEST(StixelNExTTorch, UnknownHeadLayoutNamesWhatItExpects) {
  weights::SafeTensors full = reftest::load_ref("stixel_v4_weights.safetensors");
  weights::Writer wr;
  for (const auto& name : full.names())
    if (name.rfind("classifier.", 0) != 0 || name.find("shared_reduce") != std::string::npos) {
      auto v = full.f32(name);
      wr.add_f32(name == "classifier.shared_reduce.weight" ? "classifier.mystery.weight" : name,
                 full.info(name).shape, v.data());
    }
  weights::SafeTensors st = weights::SafeTensors::from_bytes(wr.bytes(), "odd.safetensors");
  try {
    nn::StixelNExT model(st);
    FAIL() << "expected an error";
  } catch (const weights::Error& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("odd.safetensors"), std::string::npos) << msg;
    EXPECT_NE(msg.find("unknown stixel head"), std::string::npos) << msg;
    EXPECT_NE(msg.find("classifier.local_mixing.depthwise.weight"), std::string::npos) << msg;
  }
}

TEST(StixelNExTTorch, DeterministicAcrossThreadCounts) {
  weights::SafeTensors w = reftest::load_ref("stixel_v4_weights.safetensors");
  weights::SafeTensors c = reftest::load_ref("stixel_case_v4_small.safetensors");
  const auto x = c.f32("input");
  const std::size_t n = 4 * 64 * static_cast<std::size_t>(small_size().u);
  nn::set_num_threads(1);
  nn::StixelNExT one(w);
  one.plan(1, small_size().h, small_size().w, small_size().u);
  std::vector<float> a(one.forward(x.data()), one.forward(x.data()) + n);
  nn::set_num_threads(2);
  nn::StixelNExT two(w);
  two.plan(1, small_size().h, small_size().w, small_size().u);
  const float* b = two.forward(x.data());
  nn::set_num_threads(0);
  EXPECT_EQ(0, std::memcmp(a.data(), b, n * sizeof(float)));
}

}  // namespace

// Extraction end to end: stixels from our prediction against stixels from PyTorch's
// prediction of the same image (same extraction code). Sets agree apart from
// candidates within 1e-5 of the threshold; rows agree apart from v * H + 1 within
// 1e-5 of an integer; depths within 1e-5 relative.
#include "stixel/anchors.h"
#include "stixel/extract.h"

namespace {

void check_extraction(const std::string& variant, double threshold) {
  weights::SafeTensors w = reftest::load_ref("stixel_" + variant + "_weights.safetensors");
  weights::SafeTensors c = reftest::load_ref("stixel_case_" + variant + "_small.safetensors");
  nn::StixelNExT model(w);
  model.plan(1, small_size().h, small_size().w, small_size().u);
  const auto x = c.f32("input");
  const float* ours = model.forward(x.data());
  const auto theirs = c.f32("expected");
  const int attrs = model.head().attributes(), n = 64, u = small_size().u, H = small_size().h;
  stixel::ExtractOptions opt;
  opt.threshold = threshold;
  opt.image_height = H;
  const auto anchors = stixel::tangent_anchors();
  const auto a = stixel::extract(ours, attrs, n, u, anchors, opt).stixels;
  const auto b = stixel::extract(theirs.data(), attrs, n, u, anchors, opt).stixels;
  // Index both by (column, candidate): candidate order within a column is the anchor order.
  auto index = [&](const float* pred, const std::vector<stixel::Stixel>& s) {
    std::map<std::pair<int, int>, stixel::Stixel> m;
    std::size_t k = 0;
    for (int col = 0; col < u; ++col)
      for (int cand = 0; cand < n; ++cand)
        if (pred[static_cast<std::size_t>(attrs - 1) * n * u + cand * u + col] >= threshold && k < s.size())
          m[{col, cand}] = s[k++];
    return m;
  };
  const auto ma = index(ours, a), mb = index(theirs.data(), b);
  int compared = 0;
  auto near_int = [](double v) { return std::fabs(v - std::round(v)) < 1e-5 * 256; };
  for (int col = 0; col < u; ++col)
    for (int cand = 0; cand < n; ++cand) {
      const std::size_t pi = static_cast<std::size_t>(attrs - 1) * n * u + cand * u + col;
      const bool in_a = ma.count({col, cand}), in_b = mb.count({col, cand});
      if (in_a != in_b) {
        EXPECT_LT(std::fabs(theirs[pi] - threshold), 1e-5) << variant << " column " << col << " candidate " << cand;
        continue;
      }
      if (!in_a) continue;
      const auto& sa = ma.at({col, cand});
      const auto& sb = mb.at({col, cand});
      const double vb = theirs[0 * n * u + cand * u + col] * static_cast<double>(H) + 1;
      const double vt = theirs[1 * n * u + cand * u + col] * static_cast<double>(H) + 1;
      if (!near_int(vb)) {
        EXPECT_EQ(sa.vB, sb.vB) << variant << " column " << col << " candidate " << cand;
      }
      if (!near_int(vt)) {
        EXPECT_EQ(sa.vT, sb.vT) << variant << " column " << col << " candidate " << cand;
      }
      EXPECT_NEAR(sa.d, sb.d, 1e-5 * sb.d);
      EXPECT_EQ(sa.u, sb.u);
      ++compared;
    }
  EXPECT_GT(compared, 100) << "too few stixels to compare";
}

TEST(StixelNExTTorch, ExtractionV4AllCandidatesMatchesTorch) { check_extraction("v4", 0.0); }
TEST(StixelNExTTorch, ExtractionV4ThresholdMatchesTorch) { check_extraction("v4", 0.36); }
TEST(StixelNExTTorch, ExtractionV1MatchesTorch) { check_extraction("v1", 0.36); }
TEST(StixelNExTTorch, ExtractionV0MatchesTorch) { check_extraction("v0", 0.36); }

// Issue 14 item 5: on the recorded network output (PyTorch's V4 prediction of the
// same image), every candidate's d is the authors' decoding bit for bit
// (numpy float64 exp(log(anchor) + d_res), computed by stixel_head_ref.py).
void check_authors_depths(const std::string& size, int H, int U) {
  if (size != "small") {
    ROADNN_SKIP_LARGE_INPUT();
  }
  weights::SafeTensors c = reftest::load_ref("stixel_case_v4_" + size + ".safetensors");
  const auto prediction = c.f32("expected");
  const auto authors = c.f32("authors_d");
  ASSERT_EQ(authors.size(), static_cast<std::size_t>(64) * U);
  stixel::ExtractOptions opt;
  opt.threshold = 0;  // revert_class keeps every candidate
  opt.image_height = H;
  const auto s = stixel::extract(prediction.data(), 4, 64, U, stixel::tangent_anchors(), opt).stixels;
  ASSERT_EQ(s.size(), authors.size());
  std::size_t k = 0, differ = 0;
  for (int col = 0; col < U; ++col)
    for (int cand = 0; cand < 64; ++cand, ++k) {
      const float want = authors[static_cast<std::size_t>(cand) * U + col];
      if (std::memcmp(&s[k].d, &want, sizeof(float)) != 0) {
        ++differ;
        ADD_FAILURE() << size << " column " << col << " candidate " << cand << ": d " << s[k].d << " vs the authors' "
                      << want;
      }
      if (differ > 10) return;
    }
  EXPECT_EQ(differ, 0u);
}

TEST(StixelNExTTorch, DepthIsTheAuthorsDecodingBitForBitSmall) { check_authors_depths("small", small_size().h, small_size().u); }
TEST(StixelNExTTorch, DepthIsTheAuthorsDecodingBitForBitFullHd) { check_authors_depths("fullhd", 1280, 240); }

}  // namespace
