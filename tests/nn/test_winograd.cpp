// Winograd F(4x4, 3x3) convolution: the ISA transforms against the scalar ones (same
// bits), whole convolutions against the double-precision reference on every ISA (sizes
// not a multiple of the 4x4 tile, single pixels, channel counts off the vector width,
// batch 2, every epilogue order), bitwise the same for 1, 2 and 3 threads, and the
// switch back to the direct path.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "nn/activation.h"
#include "nn/conv2d.h"
#include "nn/error.h"
#include "nn/kernel_table.h"
#include "nn/threads.h"
#include "nn/winograd.h"
#include "nn/winograd_kernel.h"
#include "tests/nn/isa_param.h"
#include "tests/nn/random_data.h"

namespace {

using nntest::random_symmetric;
using nn::Act;
using nn::Shape;

nn::Conv2dParams conv3x3(int cin, int cout) {
  nn::Conv2dParams p;
  p.cin = cin, p.cout = cout, p.kh = p.kw = 3, p.pad_h = p.pad_w = 1;
  return p;
}

using InputFn = void (*)(const nn::WinogradInputTile&);
using OutputFn = void (*)(const nn::WinogradOutputTile&);

struct IsaKernels {
  nn::Isa isa;
  InputFn input;
  OutputFn output;
};

std::vector<IsaKernels> simd_kernels() {
  std::vector<IsaKernels> out;
  for (nn::Isa isa : nntest::supported_isas()) {
    if (isa == nn::Isa::Scalar) continue;
    const nn::KernelTable& t = nn::kernel_table(isa);
    out.push_back({isa, t.winograd_input_tile, t.winograd_output_tile});
  }
  return out;
}

// Channel counts below, at and around the AVX2 / AVX-512 vector widths.
const int kChannels[] = {1, 7, 8, 15, 16, 17, 33, 48};

TEST(WinogradTransforms, InputTransformMatchesScalarBitwise) {
  for (const IsaKernels& k : simd_kernels()) {
    for (int c : kChannels) {
      SCOPED_TRACE(std::string(nn::isa_name(k.isa)) + " c " + std::to_string(c));
      const std::vector<float> patch = random_symmetric(36 * static_cast<std::size_t>(c), c, 3.0f);
      const std::vector<float> zero(c, 0.0f);
      const std::ptrdiff_t stride = c + 5;  // rows of V further apart than c
      std::vector<float> want(36 * stride, -1.0f), got(want.size(), -1.0f);
      nn::WinogradInputTile t;
      for (int i = 0; i < 36; ++i) t.src[i] = i % 7 == 3 ? zero.data() : patch.data() + i * c;  // some padding
      t.c = c;
      t.xi_stride = stride;
      t.v = want.data();
      nn::winograd_input_tile_scalar(t);
      t.v = got.data();
      k.input(t);
      EXPECT_EQ(0, std::memcmp(want.data(), got.data(), want.size() * sizeof(float)));
    }
  }
}

TEST(WinogradTransforms, OutputTransformMatchesScalarBitwise) {
  for (const IsaKernels& k : simd_kernels()) {
    for (int c : kChannels) {
      for (int mode = 0; mode < 3; ++mode) {  // plain, relu before residual, relu after it
        SCOPED_TRACE(std::string(nn::isa_name(k.isa)) + " c " + std::to_string(c) + " mode " + std::to_string(mode));
        const std::ptrdiff_t stride = c + 3;
        const std::vector<float> m = random_symmetric(36 * stride, 100 + c, 2.0f);
        const std::vector<float> bias = random_symmetric(c, 200 + c, 0.5f);
        const std::vector<float> res = random_symmetric(16 * static_cast<std::size_t>(c), 300 + c);
        std::vector<float> want(16 * static_cast<std::size_t>(c), -7.0f), got(want.size(), -7.0f);
        nn::WinogradOutputTile t;
        t.m = m.data();
        t.xi_stride = stride;
        t.c = c;
        t.bias = mode == 1 ? nullptr : bias.data();
        t.relu_before = mode == 1;
        t.relu_after = mode == 2;
        auto point = [&](std::vector<float>& out) {
          for (int p = 0; p < 16; ++p) {
            t.dst[p] = p == 13 ? nullptr : out.data() + p * c;  // one pixel outside the image
            t.res[p] = mode == 0 || p == 2 ? nullptr : res.data() + p * c;
          }
        };
        point(want);
        nn::winograd_output_tile_scalar(t);
        point(got);
        k.output(t);
        EXPECT_EQ(0, std::memcmp(want.data(), got.data(), want.size() * sizeof(float)));
        EXPECT_EQ(got[13 * c], -7.0f) << "a pixel outside the image was written";
      }
    }
  }
}

struct Case {
  Shape in;
  int cout;
  Act act;
  bool residual, act_after_residual;
};

std::string label(const Case& c) {
  return "in " + nn::shape_str(c.in) + " cout " + std::to_string(c.cout) + " act " +
         std::to_string(static_cast<int>(c.act)) + (c.residual ? " +residual" : "") +
         (c.act_after_residual ? " (act after)" : "");
}

const Case kCases[] = {
    {{1, 1, 1, 16}, 16, Act::None, false, false},       // one pixel: a tile that is all padding but one
    {{1, 2, 3, 17}, 19, Act::Relu, false, false},       // smaller than a tile
    {{1, 4, 4, 16}, 32, Act::None, true, false},        // exactly one tile
    {{2, 5, 7, 33}, 40, Act::Relu, true, true},         // batch 2, tails in both directions
    {{1, 9, 13, 24}, 17, Act::HardSwish, true, false},  // activation outside the fused set
    {{1, 17, 6, 64}, 48, Act::Relu, false, false},      // several blocks of tiles per thread
    {{1, 6, 70, 20}, 80, Act::Gelu, true, true},        // wide row of tiles
    {{1, 30, 31, 19}, 21, Act::Relu, true, true},       // many tiles, odd channels
};

class WinogradConvTest : public testing::TestWithParam<nn::Isa> {};

std::vector<float> run(const Case& c, const std::vector<float>& x, const nn::Conv2dWeights& w,
                       const std::vector<float>& res, int threads) {
  nn::set_num_threads(threads);
  const Shape os{c.in.n, c.in.h, c.in.w, c.cout};
  std::vector<float> out(os.count(), 7.0f);
  nn::AlignedBuffer scratch(nn::conv2d_scratch_floats(w, os.w) * threads);
  nn::conv2d(nn::ConstTensorView(x.data(), c.in), w, nn::TensorView{out.data(), os}, scratch.data(), c.act,
             c.residual ? res.data() : nullptr, c.act_after_residual);
  nn::set_num_threads(0);
  return out;
}

TEST_P(WinogradConvTest, MatchesReferenceAndIsThreadCountIndependent) {
  nntest::IsaScope scope(GetParam());
  unsigned seed = 11;
  for (const Case& c : kCases) {
    SCOPED_TRACE(label(c));
    const nn::Conv2dParams p = conv3x3(c.in.c, c.cout);
    ASSERT_TRUE(nn::conv2d_winograd_applies(p));
    const std::vector<float> x = random_symmetric(c.in.count(), seed++);
    const std::vector<float> wt = random_symmetric(static_cast<std::size_t>(p.cout) * p.cin * 9, seed++,
                                                1.0f / std::sqrt(9.0f * p.cin));
    const std::vector<float> b = random_symmetric(p.cout, seed++, 0.1f);
    const Shape os{c.in.n, c.in.h, c.in.w, c.cout};
    const std::vector<float> res = random_symmetric(os.count(), seed++);
    const nn::Conv2dWeights w = nn::Conv2dWeights::pack(wt.data(), b.data(), p);
    ASSERT_TRUE(w.is_winograd());

    std::vector<float> want(os.count());
    nn::conv2d_ref(nn::ConstTensorView(x.data(), c.in), wt.data(), b.data(), p, nn::TensorView{want.data(), os});
    for (std::size_t i = 0; i < want.size(); ++i) {
      float v = want[i];
      if (!c.act_after_residual) v = nn::act_ref(c.act, v);
      if (c.residual) v = v + res[i];
      if (c.act_after_residual) v = nn::act_ref(c.act, v);
      want[i] = v;
    }
    const std::vector<float> one = run(c, x, w, res, 1);
    // F(4x4, 3x3) rounding: at most 5.4e-6 measured on these unit-scale outputs (direct: ~1e-6).
    double worst = 0;
    for (std::size_t i = 0; i < want.size(); ++i) worst = std::max(worst, double(std::fabs(one[i] - want[i])));
    EXPECT_LT(worst, 3e-5) << "largest |winograd - reference|";
    for (std::size_t i = 0; i < want.size(); ++i)
      ASSERT_NEAR(one[i], want[i], 3e-5f * (1.0f + std::fabs(want[i]))) << "element " << i;
    for (int threads : {2, 3}) {
      const std::vector<float> more = run(c, x, w, res, threads);
      EXPECT_EQ(0, std::memcmp(one.data(), more.data(), one.size() * sizeof(float))) << "1 vs " << threads << " threads";
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Isa, WinogradConvTest, testing::ValuesIn(nntest::supported_isas()), nntest::isa_test_name);

TEST(Winograd, OnlyThreeByThreeStrideOnePadOneWithEnoughChannels) {
  EXPECT_TRUE(nn::conv2d_winograd_applies(conv3x3(16, 16)));
  EXPECT_FALSE(nn::conv2d_winograd_applies(conv3x3(15, 64)));
  EXPECT_FALSE(nn::conv2d_winograd_applies(conv3x3(64, 8)));
  nn::Conv2dParams p = conv3x3(64, 64);
  p.stride_h = p.stride_w = 2;
  EXPECT_FALSE(nn::conv2d_winograd_applies(p));
  p = conv3x3(64, 64);
  p.pad_h = p.pad_w = 0;
  EXPECT_FALSE(nn::conv2d_winograd_applies(p));
  p = conv3x3(64, 64);
  p.kh = p.kw = 5, p.pad_h = p.pad_w = 2;
  EXPECT_FALSE(nn::conv2d_winograd_applies(p));
}

// set_winograd(false) packs the same layer for the direct GEMM; both agree closely.
TEST(Winograd, SwitchingOffPacksTheDirectForm) {
  const Case c{{1, 11, 9, 32}, 24, Act::Relu, false, false};
  const nn::Conv2dParams p = conv3x3(c.in.c, c.cout);
  const std::vector<float> x = random_symmetric(c.in.count(), 5), wt = random_symmetric(24 * 32 * 9, 6, 0.06f);
  const std::vector<float> b = random_symmetric(24, 7, 0.1f), res;
  const bool saved = nn::winograd_enabled();
  nn::set_winograd(false);
  const nn::Conv2dWeights direct = nn::Conv2dWeights::pack(wt.data(), b.data(), p);
  nn::set_winograd(true);
  const nn::Conv2dWeights wino = nn::Conv2dWeights::pack(wt.data(), b.data(), p);
  nn::set_winograd(saved);
  EXPECT_FALSE(direct.is_winograd());
  EXPECT_TRUE(wino.is_winograd());
  EXPECT_GT(wino.weight_bytes(), direct.weight_bytes());  // 36 products per 9 taps
  const std::vector<float> a = run(c, x, direct, res, 2), d = run(c, x, wino, res, 2);
  for (std::size_t i = 0; i < a.size(); ++i) ASSERT_NEAR(a[i], d[i], 3e-5f * (1.0f + std::fabs(a[i]))) << i;
}

TEST(Winograd, BadShapesThrow) {
  const nn::Conv2dParams p = conv3x3(16, 16);
  const std::vector<float> wt(16 * 16 * 9, 0.01f);
  const nn::Conv2dWeights w = nn::Conv2dWeights::pack(wt.data(), nullptr, p);
  ASSERT_TRUE(w.is_winograd());
  std::vector<float> x(4 * 4 * 16), y(4 * 4 * 16);
  nn::AlignedBuffer scratch(nn::conv2d_scratch_floats(w, 4) * 4);
  EXPECT_THROW(nn::conv2d(nn::ConstTensorView(x.data(), {1, 4, 4, 16}), w, nn::TensorView{y.data(), {1, 4, 3, 16}},
                          scratch.data()),
               nn::Error);
  EXPECT_THROW(nn::winograd_conv2d(nn::ConstTensorView(x.data(), {1, 4, 4, 16}), w.winograd(), nullptr,
                                   nn::TensorView{y.data(), {1, 4, 4, 16}}, nullptr),
               nn::Error);
  EXPECT_THROW(nn::conv2d_rows(nn::ConstTensorView(x.data(), {1, 4, 4, 16}), w, nn::TensorView{y.data(), {1, 4, 4, 16}},
                               0, 0, 4, scratch.data()),
               nn::Error);
  EXPECT_THROW(nn::WinogradWeights::pack(nullptr, 16, 16), nn::Error);
}

}  // namespace
