// Extraction against the numpy reimplementation of the reference revert
// functions (tests/reference/stixel_extract_ref.py).
#include <cmath>
#include <set>

#include "stixel/anchors.h"
#include "stixel/extract.h"
#include "tests/stixel/reftest_util.h"

TEST(ExtractRef, AnchorsEqualNumpysBitForBit) {
  const auto st = stxref::load("stixel_anchors.safetensors");
  EXPECT_EQ(stixel::tangent_anchors().depth, st.f32("tangent"));
  EXPECT_EQ(stixel::linear_anchors(5, 69, 64).depth, st.f32("linear_5_69"));
  // The float32 table is the float64 one rounded.
  const std::vector<double> exact = stxref::f64(st, "tangent_f64");
  for (int i = 0; i < 64; ++i) EXPECT_EQ(stixel::tangent_anchors().depth[i], static_cast<float>(exact[i]));
  // The double table the depth decoding starts from: numpy's np.tan is its own SIMD
  // code (AVX-512 builds) and differs from the C library's tan in the last bits, so
  // the doubles agree within a few ulp, not bit for bit; rounded to float32 (above)
  // and through the decoding (DepthIsTheAuthorsDecodingBitForBit*) they are the same.
  const auto ours = stixel::tangent_anchors().exact;
  ASSERT_EQ(ours.size(), exact.size());
  for (int i = 0; i < 64; ++i) {
    const double ulp = std::nextafter(exact[i], INFINITY) - exact[i];
    EXPECT_LE(std::fabs(ours[i] - exact[i]), 4 * ulp) << i;
  }
}

namespace {

void check_case(const std::string& name) {
  SCOPED_TRACE(name);
  const auto st = stxref::load("stixel_extract_" + name + ".safetensors");
  const auto& shape = st.info("prediction").shape;
  ASSERT_EQ(shape.size(), 3u);
  const int A = static_cast<int>(shape[0]), N = static_cast<int>(shape[1]), U = static_cast<int>(shape[2]);
  std::vector<float> pred = st.f32("prediction");
  stixel::Anchors anchors;
  anchors.depth = st.f32("anchors");
  anchors.exact = stxref::f64(st, "anchors_f64");
  stixel::ExtractOptions o;
  o.threshold = std::stod(stxref::meta(st, "threshold"));
  o.image_height = std::stoi(stxref::meta(st, "height"));
  o.stixel_width = std::stoi(stxref::meta(st, "width"));
  ASSERT_EQ(std::stoi(stxref::meta(st, "attrs")), A);

  // Candidates within 1e-5 of the threshold may go either way: remove them from
  // both sides (NaN is never kept).
  const std::size_t plane = static_cast<std::size_t>(N) * U;
  std::set<std::pair<int, int>> ambiguous;  // (column, n)
  for (int n = 0; n < N; ++n)
    for (int u = 0; u < U; ++u) {
      float& p = pred[(A - 1) * plane + static_cast<std::size_t>(n) * U + u];
      if (std::fabs(static_cast<double>(p) - o.threshold) <= 1e-5) {
        ambiguous.insert({u, n});
        p = NAN;
      }
    }
  const stixel::StixelWorld w = stixel::extract(pred.data(), A, N, U, anchors, o);

  const std::vector<int> rows = stxref::i32(st, "u_vT_vB"), ns = stxref::i32(st, "n");
  const std::vector<float> d = st.f32("d"), conf = st.f32("confidence");
  const std::vector<float> orig = st.f32("prediction");
  std::size_t k = 0, exact_rows = 0, boundary_rows = 0;
  for (std::size_t r = 0; r < ns.size(); ++r) {
    const int u = rows[3 * r] / o.stixel_width, n = ns[r];
    if (ambiguous.count({u, n})) continue;
    ASSERT_LT(k, w.stixels.size()) << "we emit fewer stixels than the reference";
    const stixel::Stixel& s = w.stixels[k++];
    ASSERT_EQ(s.u, rows[3 * r]) << "stixel " << r;
    const std::size_t i = static_cast<std::size_t>(n) * U + u;
    // Rows: exact, unless v_hat * H + 1 lies within 1e-5 of an integer.
    const int got[2] = {s.vT, s.vB}, want[2] = {rows[3 * r + 1], rows[3 * r + 2]};
    const float vhat[2] = {orig[plane + i], orig[i]};
    for (int j = 0; j < 2; ++j) {
      const double v = static_cast<double>(vhat[j]) * o.image_height + 1.0;
      if (std::fabs(v - std::round(v)) <= 1e-5) {
        ++boundary_rows;
        EXPECT_LE(std::abs(got[j] - want[j]), 1) << "stixel " << r;
      } else {
        ++exact_rows;
        EXPECT_EQ(got[j], want[j]) << "stixel " << r << (j ? " vB" : " vT");
      }
    }
    // The authors' decoding in double: the same float32 bits.
    EXPECT_EQ(s.d, d[r]) << "stixel " << r << " d";
    EXPECT_EQ(s.confidence, conf[r]) << "stixel " << r;
    EXPECT_EQ(s.width, o.stixel_width);
  }
  EXPECT_EQ(k, w.stixels.size()) << "we emit more stixels than the reference";
  EXPECT_GT(exact_rows, 1000u);
  ::testing::Test::RecordProperty("boundary_rows_" + name, static_cast<int>(boundary_rows));
}

}  // namespace

TEST(ExtractRef, V4AllCandidates) { check_case("v4_all"); }
TEST(ExtractRef, V4Threshold036) { check_case("v4_036"); }
TEST(ExtractRef, V3Threshold036WithNaN) { check_case("v3_036_nan"); }
TEST(ExtractRef, CoopScenes120Columns) { check_case("v1_coop"); }
