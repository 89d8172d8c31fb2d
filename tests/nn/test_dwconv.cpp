// Depthwise convolution kernels against the scalar reference, on every ISA, on
// awkward shapes; thread-count determinism; parameter errors.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "nn/dwconv.h"
#include "nn/error.h"
#include "nn/threads.h"
#include "tests/nn/isa_param.h"
#include "tests/nn/random_data.h"

namespace {

using nntest::random_vector;
using nn::Act;
using nn::DwConvParams;
using nn::Shape;

DwConvParams make(int kh, int kw, int s, int ph, int pw, Act act = Act::None) {
  DwConvParams p;
  p.kh = kh;
  p.kw = kw;
  p.stride_h = p.stride_w = s;
  p.pad_h = ph;
  p.pad_w = pw;
  p.act = act;
  return p;
}

bool valid_for(const Shape& in, const DwConvParams& p) {
  return in.h + 2 * p.pad_h >= p.kh && in.w + 2 * p.pad_w >= p.kw;
}

std::string label(const Shape& s, const DwConvParams& p) {
  return "in [" + std::to_string(s.n) + "," + std::to_string(s.h) + "," + std::to_string(s.w) +
         "," + std::to_string(s.c) + "] k " + std::to_string(p.kh) + "x" + std::to_string(p.kw) +
         " s" + std::to_string(p.stride_h) + " p" + std::to_string(p.pad_h) + "," +
         std::to_string(p.pad_w) + " act " + std::to_string(static_cast<int>(p.act));
}

// Runs the packed kernel for the active ISA and checks it against dwconv_ref:
// |y - ref| <= 1e-5 * (sum |x||w| + |b|) (times 1.5, HardSwish's largest slope);
// the scalar path must match the reference bit for bit.
void check_case(nn::Isa isa, const Shape& in_shape, const DwConvParams& p, bool with_bias,
                unsigned seed) {
  SCOPED_TRACE(label(in_shape, p));
  const int c = in_shape.c;
  const std::vector<float> x = random_vector(in_shape.count(), seed);
  const std::vector<float> w = random_vector(static_cast<std::size_t>(c) * p.kh * p.kw, seed + 1);
  const std::vector<float> b = random_vector(c, seed + 2, -0.5f, 0.5f);
  const float* bias = with_bias ? b.data() : nullptr;

  const Shape os = nn::dwconv_output_shape(in_shape, p);
  std::vector<float> got(os.count(), std::nanf("")), want(os.count()), bound(os.count());
  const nn::DwConvWeights packed = nn::DwConvWeights::pack(w.data(), bias, c, p);
  ASSERT_EQ(packed.isa(), isa);
  nn::dwconv(nn::ConstTensorView(x.data(), in_shape), packed, nn::TensorView{got.data(), os});
  nn::dwconv_ref(nn::ConstTensorView(x.data(), in_shape), w.data(), bias, p,
                 nn::TensorView{want.data(), os});

  std::vector<float> ax(x.size()), aw(w.size()), ab(b.size());
  for (std::size_t i = 0; i < x.size(); ++i) ax[i] = std::fabs(x[i]);
  for (std::size_t i = 0; i < w.size(); ++i) aw[i] = std::fabs(w[i]);
  for (std::size_t i = 0; i < b.size(); ++i) ab[i] = std::fabs(b[i]);
  DwConvParams pa = p;
  pa.act = Act::None;
  nn::dwconv_ref(nn::ConstTensorView(ax.data(), in_shape), aw.data(), with_bias ? ab.data() : nullptr,
                 pa, nn::TensorView{bound.data(), os});

  if (isa == nn::Isa::Scalar) {
    ASSERT_EQ(0, std::memcmp(got.data(), want.data(), got.size() * sizeof(float)));
    return;
  }
  const float slope = p.act == Act::HardSwish ? 1.5f : 1.0f;
  int bad = 0;
  for (std::size_t i = 0; i < got.size() && bad < 5; ++i) {
    const float tol = 1e-5f * slope * bound[i] + 1e-30f;
    if (!(std::fabs(got[i] - want[i]) <= tol)) {
      ++bad;
      ADD_FAILURE() << "element " << i << " (pixel " << i / c << ", channel " << i % c
                    << "): got " << got[i] << ", reference " << want[i] << ", tolerance " << tol;
    }
  }
}

// A random input and packed random weights with bias for one layer (seeds seed..seed+2).
struct RandomLayer {
  std::vector<float> x;
  nn::DwConvWeights packed;
};
RandomLayer random_layer(const Shape& in, const DwConvParams& p, unsigned seed) {
  const std::vector<float> w = random_vector(static_cast<std::size_t>(in.c) * p.kh * p.kw, seed + 1);
  const std::vector<float> b = random_vector(in.c, seed + 2);
  return {random_vector(in.count(), seed), nn::DwConvWeights::pack(w.data(), b.data(), in.c, p)};
}

class DwConvTest : public testing::TestWithParam<nn::Isa> {};

// Every kernel shape the models use, plus generic ones (run-time kernel width and
// stride) and padding wider than the kernel.
const std::vector<DwConvParams>& all_kernels() {
  static const std::vector<DwConvParams> k = {
      make(7, 7, 1, 3, 3),  // ConvNeXt
      make(1, 5, 1, 0, 2),  // StixelNExT++ V4 head
      make(3, 3, 1, 1, 1), make(3, 3, 2, 1, 1),  // MobileNetV3
      make(5, 5, 1, 2, 2), make(5, 5, 2, 2, 2),
      make(7, 7, 2, 3, 3), make(2, 4, 1, 0, 1), make(1, 1, 1, 0, 0), make(3, 3, 1, 4, 4),
  };
  return k;
}

TEST_P(DwConvTest, MatchesReferenceOnAwkwardShapes) {
  nntest::IsaScope scope(GetParam());
  const int cs[] = {1, 5, 15, 16, 17, 33, 96, 100};
  const int ws[] = {1, 2, 3, 6, 7, 8, 13, 14, 15, 29, 61};
  const int hs[] = {1, 2, 7, 9};
  const Act acts[] = {Act::None, Act::Relu, Act::HardSwish};
  unsigned seed = 1;
  int k_index = 0;
  for (const DwConvParams& base : all_kernels()) {
    for (int ci = 0; ci < 8; ++ci)
      for (int wi = 0; wi < 11; ++wi) {
        // Every (C, W) pair once per kernel, cycling H and the activation through it.
        const Shape in{2, hs[(ci + wi + k_index) % 4], ws[wi], cs[ci]};
        DwConvParams p = base;
        p.act = acts[(ci + 2 * wi + k_index) % 3];
        if (!valid_for(in, p)) continue;
        check_case(GetParam(), in, p, (ci + wi) % 4 != 0, seed += 3);
        if (HasFatalFailure()) return;
      }
    ++k_index;
  }
}

// Rows wide enough for several tiles along W, and a tall image with every activation.
TEST_P(DwConvTest, MatchesReferenceOnWideRows) {
  nntest::IsaScope scope(GetParam());
  unsigned seed = 1000;
  for (const DwConvParams& base : all_kernels())
    for (Act act : {Act::None, Act::Relu, Act::HardSwish}) {
      DwConvParams p = base;
      p.act = act;
      check_case(GetParam(), Shape{1, 6, 300, 24}, p, true, seed += 3);
      if (HasFatalFailure()) return;
    }
  check_case(GetParam(), Shape{1, 40, 33, 40}, make(7, 7, 1, 3, 3, Act::HardSwish), true, 77);
}

// Every output must come out the same bits whatever the thread count.
TEST_P(DwConvTest, BitwiseIdenticalForOneAndTwoThreads) {
  nntest::IsaScope scope(GetParam());
  const int saved = nn::num_threads();
  const DwConvParams kernels[] = {make(7, 7, 1, 3, 3), make(3, 3, 2, 1, 1, Act::HardSwish),
                                   make(1, 5, 1, 0, 2, Act::Relu), make(7, 7, 2, 3, 3)};
  // The second shape is too short for row chunks alone: threads get channel groups.
  for (const Shape& in : {Shape{2, 37, 45, 40}, Shape{1, 9, 20, 100}}) {
    for (const DwConvParams& p : kernels) {
      SCOPED_TRACE(label(in, p));
      const RandomLayer layer = random_layer(in, p, 5);
      const std::vector<float>& x = layer.x;
      const nn::DwConvWeights& packed = layer.packed;
      const Shape os = nn::dwconv_output_shape(in, p);
      std::vector<float> one(os.count()), two(os.count(), 1.0f);
      nn::set_num_threads(1);
      nn::dwconv(nn::ConstTensorView(x.data(), in), packed, nn::TensorView{one.data(), os});
      nn::set_num_threads(2);
      nn::dwconv(nn::ConstTensorView(x.data(), in), packed, nn::TensorView{two.data(), os});
      EXPECT_EQ(0, std::memcmp(one.data(), two.data(), one.size() * sizeof(float)));
    }
  }
  nn::set_num_threads(saved);
}

// dwconv_rows (a band of one image's rows into a dense buffer, as ConvNeXt's banded
// blocks call it) writes bitwise what dwconv writes for those rows: every band of 1, 3
// and 8 rows, for images 0 and 1, and nothing outside the band.
TEST_P(DwConvTest, RowBandsEqualTheWholeMapBitwise) {
  nntest::IsaScope scope(GetParam());
  const DwConvParams kernels[] = {make(7, 7, 1, 3, 3), make(3, 3, 2, 1, 1, Act::HardSwish),
                                   make(1, 5, 1, 0, 2, Act::Relu)};
  for (const Shape& in : {Shape{2, 19, 37, 40}, Shape{2, 5, 13, 17}}) {
    for (const DwConvParams& p : kernels) {
      SCOPED_TRACE(label(in, p));
      const RandomLayer layer = random_layer(in, p, 21);
      const std::vector<float>& x = layer.x;
      const nn::DwConvWeights& packed = layer.packed;
      const Shape os = nn::dwconv_output_shape(in, p);
      std::vector<float> whole(os.count());
      nn::dwconv(nn::ConstTensorView(x.data(), in), packed, nn::TensorView{whole.data(), os});
      const std::size_t row = static_cast<std::size_t>(os.w) * os.c;
      for (int band : {1, 3, 8})
        for (int n = 0; n < os.n; ++n)
          for (int y0 = 0; y0 < os.h; y0 += band) {
            const int y1 = std::min(os.h, y0 + band);
            // One guard row after the band: it must stay untouched.
            std::vector<float> got((y1 - y0 + 1) * row, -7.0f);
            nn::dwconv_rows(nn::ConstTensorView(x.data(), in), packed, n, y0, y1, got.data());
            const float* want = whole.data() + (static_cast<std::size_t>(n) * os.h + y0) * row;
            ASSERT_EQ(0, std::memcmp(got.data(), want, (y1 - y0) * row * sizeof(float)))
                << "band " << band << " image " << n << " rows " << y0 << ".." << y1;
            for (std::size_t i = (y1 - y0) * row; i < got.size(); ++i) ASSERT_EQ(got[i], -7.0f) << i;
          }
    }
  }
}

// Weights keep the layout of the ISA they were packed for, whatever is active later.
TEST_P(DwConvTest, PackedWeightsKeepTheirIsa) {
  const DwConvParams p = make(3, 3, 1, 1, 1);
  const Shape in{1, 5, 9, 20};
  const std::vector<float> x = random_vector(in.count(), 11);
  const std::vector<float> w = random_vector(static_cast<std::size_t>(in.c) * 9, 12);
  nn::DwConvWeights packed;
  {
    nntest::IsaScope scope(GetParam());
    packed = nn::DwConvWeights::pack(w.data(), nullptr, in.c, p);
  }
  nntest::IsaScope scalar(nn::Isa::Scalar);
  const Shape os = nn::dwconv_output_shape(in, p);
  std::vector<float> got(os.count()), want(os.count());
  nn::dwconv(nn::ConstTensorView(x.data(), in), packed, nn::TensorView{got.data(), os});
  nn::dwconv_ref(nn::ConstTensorView(x.data(), in), w.data(), nullptr, p,
                 nn::TensorView{want.data(), os});
  for (std::size_t i = 0; i < got.size(); ++i) EXPECT_NEAR(got[i], want[i], 1e-5f) << i;
}

INSTANTIATE_TEST_SUITE_P(Isa, DwConvTest, testing::ValuesIn(nntest::supported_isas()),
                         nntest::isa_test_name);

TEST(DwConvErrors, UnfusableActivationIsRejectedAtPack) {
  const std::vector<float> w(9 * 4, 0.1f);
  for (Act act : {Act::Gelu, Act::Sigmoid, Act::HardSigmoid}) {
    try {
      nn::DwConvWeights::pack(w.data(), nullptr, 4, make(3, 3, 1, 1, 1, act));
      FAIL() << "activation " << static_cast<int>(act) << " accepted";
    } catch (const nn::Error& e) {
      EXPECT_NE(std::string(e.what()).find("separately"), std::string::npos) << e.what();
    }
  }
}

TEST(DwConvErrors, BadParametersThrow) {
  const std::vector<float> w(64 * 64 * 2, 0.1f);
  EXPECT_THROW(nn::DwConvWeights::pack(w.data(), nullptr, 2, make(0, 3, 1, 1, 1)), nn::Error);
  EXPECT_THROW(nn::DwConvWeights::pack(w.data(), nullptr, 2, make(3, 33, 1, 1, 1)), nn::Error);
  EXPECT_THROW(nn::DwConvWeights::pack(w.data(), nullptr, 2, make(3, 3, 0, 1, 1)), nn::Error);
  EXPECT_THROW(nn::DwConvWeights::pack(w.data(), nullptr, 2, make(3, 3, 1, -1, 1)), nn::Error);
  EXPECT_THROW(nn::DwConvWeights::pack(w.data(), nullptr, 0, make(3, 3, 1, 1, 1)), nn::Error);
  EXPECT_THROW(nn::DwConvWeights::pack(nullptr, nullptr, 2, make(3, 3, 1, 1, 1)), nn::Error);
  // Input smaller than an unpadded kernel.
  EXPECT_THROW(nn::dwconv_output_shape(Shape{1, 2, 9, 2}, make(3, 3, 1, 0, 0)), nn::Error);
}

TEST(DwConvErrors, MismatchedTensorsThrow) {
  const DwConvParams p = make(3, 3, 1, 1, 1);
  const std::vector<float> w(9 * 4, 0.1f);
  const nn::DwConvWeights packed = nn::DwConvWeights::pack(w.data(), nullptr, 4, p);
  std::vector<float> x(1 * 5 * 5 * 4, 1.0f), y(x.size()), y3(5 * 5 * 3);
  const Shape s{1, 5, 5, 4};
  // Wrong output shape, channel count mismatch, output overlapping the input.
  EXPECT_THROW(nn::dwconv(nn::ConstTensorView(x.data(), s), packed,
                          nn::TensorView{y.data(), Shape{1, 4, 5, 4}}),
               nn::Error);
  EXPECT_THROW(nn::dwconv(nn::ConstTensorView(y3.data(), Shape{1, 5, 5, 3}), packed,
                          nn::TensorView{y.data(), Shape{1, 5, 5, 3}}),
               nn::Error);
  EXPECT_THROW(nn::dwconv(nn::ConstTensorView(x.data(), s), packed, nn::TensorView{x.data(), s}),
               nn::Error);
  EXPECT_THROW(nn::dwconv(nn::ConstTensorView(x.data(), s), nn::DwConvWeights(),
                          nn::TensorView{y.data(), s}),
               nn::Error);
  EXPECT_NO_THROW(nn::dwconv(nn::ConstTensorView(x.data(), s), packed, nn::TensorView{y.data(), s}));
  // dwconv_rows: rows or image outside the output, reversed rows, overlap, no weights,
  // channel mismatch.
  const nn::ConstTensorView xv(x.data(), s);
  EXPECT_THROW(nn::dwconv_rows(xv, packed, 0, 4, 6, y.data()), nn::Error);
  EXPECT_THROW(nn::dwconv_rows(xv, packed, 1, 0, 1, y.data()), nn::Error);
  EXPECT_THROW(nn::dwconv_rows(xv, packed, 0, -1, 1, y.data()), nn::Error);
  EXPECT_THROW(nn::dwconv_rows(xv, packed, 0, 3, 2, y.data()), nn::Error);
  EXPECT_THROW(nn::dwconv_rows(xv, packed, 0, 0, 2, x.data() + 20), nn::Error);
  EXPECT_THROW(nn::dwconv_rows(xv, nn::DwConvWeights(), 0, 0, 1, y.data()), nn::Error);
  EXPECT_THROW(nn::dwconv_rows(nn::ConstTensorView(y3.data(), Shape{1, 5, 5, 3}), packed, 0, 0, 1, y.data()),
               nn::Error);
  // A zero-width input (its output shape is not positive either) and null pointers.
  EXPECT_THROW(nn::dwconv_rows(nn::ConstTensorView(x.data(), Shape{1, 5, 0, 4}), packed, 0, 0, 1, y.data()),
               nn::Error);
  EXPECT_THROW(nn::dwconv_rows(nn::ConstTensorView(nullptr, s), packed, 0, 0, 1, y.data()), nn::Error);
  EXPECT_THROW(nn::dwconv_rows(xv, packed, 0, 0, 1, nullptr), nn::Error);
  EXPECT_NO_THROW(nn::dwconv_rows(xv, packed, 0, 2, 5, y.data()));
  EXPECT_NO_THROW(nn::dwconv_rows(xv, packed, 0, 5, 5, y.data()));
}

// A constant image and kernel: interior outputs are k*k*x*w + b exactly, borders
// count only the taps inside the image (zero padding).
TEST(DwConvValues, ZeroPaddingCountsOnlyInsideTaps) {
  for (nn::Isa isa : nntest::supported_isas()) {
    nntest::IsaScope scope(isa);
    const DwConvParams p = make(7, 7, 1, 3, 3);
    const Shape s{1, 9, 10, 17};
    const std::vector<float> x(s.count(), 1.0f), w(17 * 49, 0.5f), b(17, 0.25f);
    std::vector<float> y(s.count());
    nn::dwconv(nn::ConstTensorView(x.data(), s), nn::DwConvWeights::pack(w.data(), b.data(), 17, p),
               nn::TensorView{y.data(), s});
    for (int oy = 0; oy < s.h; ++oy)
      for (int ox = 0; ox < s.w; ++ox) {
        const int rows = std::min(oy + 3, s.h - 1) - std::max(oy - 3, 0) + 1;
        const int cols = std::min(ox + 3, s.w - 1) - std::max(ox - 3, 0) + 1;
        for (int ch = 0; ch < s.c; ++ch)
          ASSERT_EQ(y[(oy * s.w + ox) * s.c + ch], 0.5f * rows * cols + 0.25f)
              << nn::isa_name(isa) << " at " << oy << "," << ox << "," << ch;
      }
  }
}

}  // namespace
