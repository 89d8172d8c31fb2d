// Activations: the scalar definitions against PyTorch values and double-precision
// formulas, the vector kernels of every ISA against them (dense sweep, extremes, inf,
// NaN, denormals), and tails.
#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "nn/activation.h"
#include "tests/nn/isa_param.h"

namespace {

using nn::Act;

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

double exact(Act act, float xf) {
  const double x = xf;
  switch (act) {
    case Act::Gelu: return 0.5 * x * std::erfc(-x / std::sqrt(2.0));
    case Act::Sigmoid: return 1.0 / (1.0 + std::exp(-x));
    default: return nn::act_ref(act, xf);
  }
}

float from_bits(std::uint32_t b) {
  float f;
  std::memcpy(&f, &b, sizeof f);
  return f;
}

// Dense sweep of [-10, 10] (every 331st float and a uniform grid), plus extremes.
std::vector<float> sweep_inputs() {
  std::vector<float> x;
  const std::uint32_t ten = 0x41200000u;  // 10.0f
  for (std::uint32_t b = 0; b <= ten; b += 331) {
    x.push_back(from_bits(b));
    x.push_back(-from_bits(b));
  }
  for (int i = -1000000; i <= 1000000; ++i) x.push_back(i * 1e-5f);
  const float extremes[] = {0.0f, -0.0f, FLT_MIN, -FLT_MIN, 1e-40f, -1e-40f, 1e-45f, -1e-45f,
                            FLT_MAX, -FLT_MAX, 1e30f, -1e30f, 1e10f, -1e10f, 88.0f, -88.0f,
                            89.0f, -89.0f, 104.0f, -104.0f, 5.999f, 6.0f, 6.001f, -5.999f,
                            -6.0f, -6.001f, 20.0f, -20.0f, 3.0f, -3.0f};
  x.insert(x.end(), std::begin(extremes), std::end(extremes));
  return x;
}

TEST(ActivationRef, MatchesPyTorchValues) {
  // torch 1.13 on CPU, float32: F.gelu / torch.sigmoid / F.hardswish / F.hardsigmoid in float32.
  EXPECT_NEAR(nn::act_ref(Act::Gelu, 1.0f), 8.413447142e-01, 1e-7);
  EXPECT_NEAR(nn::act_ref(Act::Gelu, -1.0f), -1.586552858e-01, 1e-7);
  EXPECT_NEAR(nn::act_ref(Act::Gelu, 2.5f), 2.484475851, 3e-7);
  // PyTorch's float 1 + erf(x / sqrt 2) cancels in the left tail (exact: -1.2668497e-4).
  EXPECT_NEAR(nn::act_ref(Act::Gelu, -4.0f), -1.267194748e-04, 1e-7);
  EXPECT_NEAR(nn::act_ref(Act::Sigmoid, 1.0f), 0.731058598, 1e-7);
  EXPECT_NEAR(nn::act_ref(Act::Sigmoid, -4.0f), 0.017986210, 1e-8);
  // The piecewise-linear ones are PyTorch's float arithmetic: equal bits.
  EXPECT_EQ(nn::act_ref(Act::HardSwish, 1.0f), 0.666666687f);
  EXPECT_EQ(nn::act_ref(Act::HardSwish, -2.0f), -0.333333343f);
  EXPECT_EQ(nn::act_ref(Act::HardSwish, 2.5f), 2.291666746f);
  EXPECT_EQ(nn::act_ref(Act::HardSwish, 4.0f), 4.0f);
  EXPECT_EQ(nn::act_ref(Act::HardSigmoid, 1.0f), 0.666666687f);
  EXPECT_EQ(nn::act_ref(Act::HardSigmoid, -2.0f), 0.166666672f);
  EXPECT_EQ(nn::act_ref(Act::HardSigmoid, -4.0f), 0.0f);
  EXPECT_FLOAT_EQ(nn::act_ref(Act::Relu, -2.0f), 0.0f);
  EXPECT_FLOAT_EQ(nn::act_ref(Act::Relu, 2.0f), 2.0f);
  EXPECT_FLOAT_EQ(nn::act_ref(Act::None, -2.5f), -2.5f);
  // PyTorch's definitions at the edges.
  EXPECT_TRUE(std::isnan(nn::act_ref(Act::Gelu, -kInf)));
  EXPECT_EQ(nn::act_ref(Act::Gelu, kInf), kInf);
  EXPECT_EQ(nn::act_ref(Act::Sigmoid, -kInf), 0.0f);
  EXPECT_EQ(nn::act_ref(Act::Sigmoid, kInf), 1.0f);
  EXPECT_TRUE(std::isnan(nn::act_ref(Act::HardSwish, -kInf)));
  EXPECT_TRUE(std::signbit(nn::act_ref(Act::Relu, -0.0f)));
  for (Act act : {Act::Relu, Act::Gelu, Act::HardSwish, Act::HardSigmoid, Act::Sigmoid})
    EXPECT_TRUE(std::isnan(nn::act_ref(act, kNaN))) << static_cast<int>(act);
}

class ActivationTest : public testing::TestWithParam<nn::Isa> {};

// apply_act against the exact function: GELU within 1e-6 absolute, sigmoid within 1e-7;
// the piecewise-linear ones (plain float arithmetic) bit for bit against act_ref.
TEST_P(ActivationTest, MatchesDefinitionsOnDenseSweepAndExtremes) {
  nntest::IsaScope scope(GetParam());
  const std::vector<float> x = sweep_inputs();
  for (Act act :
       {Act::None, Act::Relu, Act::Gelu, Act::HardSwish, Act::HardSigmoid, Act::Sigmoid}) {
    SCOPED_TRACE(static_cast<int>(act));
    std::vector<float> y = x;
    nn::apply_act(act, y.data(), y.size());
    const double tol = act == Act::Gelu ? 1e-6 : act == Act::Sigmoid ? 1e-7 : 0.0;
    int failures = 0;
    for (std::size_t i = 0; i < x.size() && failures < 10; ++i) {
      const double want = exact(act, x[i]);
      const bool ok = std::isnan(want) ? std::isnan(y[i])
                      : std::isinf(want) ? y[i] == want
                                         : std::fabs(y[i] - want) <= tol;
      if (!ok && ++failures <= 10)
        ADD_FAILURE() << "x " << x[i] << ": got " << y[i] << ", want " << want;
    }
  }
}

TEST_P(ActivationTest, InfinitiesAndNaNFollowPyTorch) {
  nntest::IsaScope scope(GetParam());
  for (Act act : {Act::Relu, Act::Gelu, Act::HardSwish, Act::HardSigmoid, Act::Sigmoid}) {
    SCOPED_TRACE(static_cast<int>(act));
    std::vector<float> y(19, kNaN);  // a full vector and a tail on every ISA
    y[3] = kInf;
    y[17] = -kInf;
    nn::apply_act(act, y.data(), y.size());
    for (std::size_t i = 0; i < y.size(); ++i) {
      const float x = i == 3 ? kInf : i == 17 ? -kInf : kNaN;
      const float want = nn::act_ref(act, x);
      if (std::isnan(want))
        EXPECT_TRUE(std::isnan(y[i])) << "x " << x << " got " << y[i];
      else
        EXPECT_EQ(y[i], want) << "x " << x;
    }
  }
}

// Every length 0..70 (masked tails) gives the same bits as the same values inside a long
// array, and nothing past the end is touched.
TEST_P(ActivationTest, TailsMatchTheMainLoopAndStayInBounds) {
  nntest::IsaScope scope(GetParam());
  std::mt19937 gen(5);
  std::uniform_real_distribution<float> dist(-8.0f, 8.0f);
  std::vector<float> base(70);
  for (auto& v : base) v = dist(gen);
  for (Act act : {Act::Relu, Act::Gelu, Act::HardSwish, Act::HardSigmoid, Act::Sigmoid}) {
    std::vector<float> full = base;
    nn::apply_act(act, full.data(), full.size());
    for (std::size_t n = 0; n <= base.size(); ++n) {
      std::vector<float> y = base;
      y.push_back(1234.5f);
      nn::apply_act(act, y.data(), n);
      for (std::size_t i = 0; i < n; ++i)
        ASSERT_EQ(0, std::memcmp(&y[i], &full[i], sizeof(float)))
            << "act " << static_cast<int>(act) << " n " << n << " i " << i;
      for (std::size_t i = n; i < base.size(); ++i) ASSERT_EQ(y[i], base[i]);
      ASSERT_EQ(y.back(), 1234.5f);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(AllIsas, ActivationTest, testing::ValuesIn(nntest::supported_isas()),
                         nntest::isa_test_name);

TEST(ActivationRef, ApplyActRefIsActRefPerElement) {
  std::vector<float> x = {-3.0f, -0.5f, 0.0f, 0.7f, 2.0f, 9.0f};
  std::vector<float> y = x;
  nn::apply_act_ref(Act::Gelu, y.data(), y.size());
  for (std::size_t i = 0; i < x.size(); ++i) EXPECT_EQ(y[i], nn::act_ref(Act::Gelu, x[i]));
  std::vector<float> z = x;
  nn::apply_act_ref(Act::None, z.data(), z.size());
  EXPECT_EQ(z, x);
}

}  // namespace
