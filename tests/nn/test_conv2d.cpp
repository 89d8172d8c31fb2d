// Dense convolution (im2col + packed GEMM in blocks of output rows) against the
// scalar reference, on every ISA: widths below and above the row-block size, heights
// that leave a short last block, batch 2, strides, padding, the residual epilogue;
// bitwise the same for 1 and 2 threads.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "nn/activation.h"
#include "nn/conv2d.h"
#include "nn/threads.h"
#include "tests/nn/isa_param.h"
#include "tests/nn/random_data.h"

namespace {

using nntest::random_symmetric;
using nn::Act;
using nn::Conv2dParams;
using nn::Shape;

Conv2dParams conv(int cin, int cout, int k, int stride, int pad) {
  Conv2dParams p;
  p.cin = cin, p.cout = cout, p.kh = p.kw = k, p.stride_h = p.stride_w = stride, p.pad_h = p.pad_w = pad;
  return p;
}

struct Case {
  Shape in;
  Conv2dParams p;
  Act act;
  bool residual;
};

std::string label(const Case& c) {
  return "in " + nn::shape_str(c.in) + " k" + std::to_string(c.p.kh) + " s" + std::to_string(c.p.stride_h) + " p" +
         std::to_string(c.p.pad_h) + " cout " + std::to_string(c.p.cout) + (c.residual ? " +residual" : "");
}

// Runs the optimized conv with `threads` threads; residual (if any) is added after
// the activation unless act_after_residual, as in nn/gemm.h.
std::vector<float> run(const Case& c, const std::vector<float>& x, const nn::Conv2dWeights& w,
                       const std::vector<float>& res, int threads) {
  nn::set_num_threads(threads);
  const Shape os = nn::conv2d_output_shape(c.in, c.p);
  std::vector<float> out(os.count(), 7.0f);
  nn::AlignedBuffer scratch(nn::conv2d_scratch_floats(w, os.w) * 2 + 1);
  nn::conv2d(nn::ConstTensorView(x.data(), c.in), w, nn::TensorView{out.data(), os}, scratch.data(), c.act,
             c.residual ? res.data() : nullptr, c.residual);
  nn::set_num_threads(0);
  return out;
}

class Conv2dTest : public testing::TestWithParam<nn::Isa> {};

TEST_P(Conv2dTest, MatchesReferenceAndIsThreadCountIndependent) {
  nntest::IsaScope scope(GetParam());
  const std::vector<Case> cases = {
      {{1, 9, 11, 17}, conv(17, 19, 3, 1, 1), Act::Relu, false},     // narrow: multi-row blocks
      {{2, 13, 17, 20}, conv(20, 36, 2, 2, 0), Act::None, false},    // batch 2, stride 2
      {{1, 5, 130, 33}, conv(33, 50, 3, 1, 1), Act::Relu, true},     // wider than one block
      {{1, 23, 29, 3}, conv(3, 16, 7, 2, 3), Act::Relu, false},      // ResNet stem shape
      {{1, 7, 42, 64}, conv(64, 40, 3, 2, 1), Act::None, true},      // short last block
      {{1, 31, 5, 24}, conv(24, 24, 1, 1, 0), Act::HardSwish, true}, // pointwise, tall and narrow
      {{1, 3, 200, 8}, conv(8, 70, 1, 2, 0), Act::None, false},      // strided 1x1 (downsample)
      {{1, 1, 1, 5}, conv(5, 7, 3, 1, 1), Act::Relu, false},         // one pixel, all padding
  };
  unsigned seed = 1;
  for (const Case& c : cases) {
    SCOPED_TRACE(label(c));
    const Conv2dParams& p = c.p;
    const std::vector<float> x = random_symmetric(c.in.count(), seed++);
    const std::vector<float> wt = random_symmetric(static_cast<std::size_t>(p.cout) * p.cin * p.kh * p.kw, seed++,
                                                1.0f / std::sqrt(static_cast<float>(p.cin * p.kh * p.kw)));
    const std::vector<float> b = random_symmetric(p.cout, seed++, 0.1f);
    const Shape os = nn::conv2d_output_shape(c.in, p);
    const std::vector<float> res = random_symmetric(os.count(), seed++);
    const nn::Conv2dWeights w = nn::Conv2dWeights::pack(wt.data(), b.data(), p);

    // Reference: conv without activation, then residual, then the activation.
    std::vector<float> want(os.count());
    nn::conv2d_ref(nn::ConstTensorView(x.data(), c.in), wt.data(), b.data(), p, nn::TensorView{want.data(), os},
                   c.residual ? Act::None : c.act);
    if (c.residual)
      for (std::size_t i = 0; i < want.size(); ++i) want[i] = nn::act_ref(c.act, want[i] + res[i]);

    const std::vector<float> one = run(c, x, w, res, 1), two = run(c, x, w, res, 2);
    for (std::size_t i = 0; i < want.size(); ++i)
      ASSERT_NEAR(one[i], want[i], 2e-5f * (1.0f + std::fabs(want[i]))) << "element " << i;
    EXPECT_EQ(0, std::memcmp(one.data(), two.data(), one.size() * sizeof(float))) << "1 vs 2 threads";
  }
}

INSTANTIATE_TEST_SUITE_P(Isa, Conv2dTest, testing::ValuesIn(nntest::supported_isas()), nntest::isa_test_name);

}  // namespace
