// Nearest and bilinear resizing against outputs of PyTorch 1.13 (embedded below),
// the scalar and AVX2 bilinear paths against each other, and argument errors.
#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <vector>

#include "nn/error.h"
#include "nn/resize.h"
#include "nn/threads.h"
#include "tests/nn/isa_param.h"

namespace {

using nn::Shape;

// Source column chosen for each output column, from
//   F.interpolate(torch.arange(in).view(1,1,1,in), size=(1,out), mode='nearest').
struct NearestCase {
  int in, out;
  std::vector<int> src;
};

TEST(Resize, NearestPicksPyTorchsSourceIndices) {
  const std::vector<NearestCase> cases = {
      {5, 13, {0, 0, 0, 1, 1, 1, 2, 2, 3, 3, 3, 4, 4}},
      {7, 3, {0, 2, 4}},
      {3, 8, {0, 0, 0, 1, 1, 1, 2, 2}},
      {10, 25, {0, 0, 0, 1, 1, 2, 2, 2, 3, 3, 4, 4, 4, 5, 5, 6, 6, 6, 7, 7, 8, 8, 8, 9, 9}},
      {6, 12, {0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 5, 5}},
      {9, 9, {0, 1, 2, 3, 4, 5, 6, 7, 8}},
      {17, 6, {0, 2, 5, 8, 11, 14}},
  };
  for (const NearestCase& k : cases) {
    // The same rule along both axes; two channels carry the row and column index.
    const Shape is{1, k.in, k.in, 2}, os{1, k.out, k.out, 2};
    std::vector<float> x(is.count()), y(os.count());
    for (int r = 0; r < k.in; ++r)
      for (int c = 0; c < k.in; ++c) {
        x[(r * k.in + c) * 2] = static_cast<float>(r);
        x[(r * k.in + c) * 2 + 1] = static_cast<float>(c);
      }
    nn::upsample_nearest(nn::ConstTensorView(x.data(), is), nn::TensorView{y.data(), os});
    for (int r = 0; r < k.out; ++r)
      for (int c = 0; c < k.out; ++c) {
        ASSERT_EQ(y[(r * k.out + c) * 2], k.src[r]) << k.in << "->" << k.out;
        ASSERT_EQ(y[(r * k.out + c) * 2 + 1], k.src[c]) << k.in << "->" << k.out;
      }
  }
}

TEST(Resize, NearestWithScaleFactorUsesItsInverse) {
  // F.interpolate(x, scale_factor=(1.0, 1.7), mode='nearest') on width 7 -> 11.
  const std::vector<int> want = {0, 0, 1, 1, 2, 2, 3, 4, 4, 5, 5};
  const Shape is{1, 1, 7, 1}, os{1, 1, 11, 1};
  std::vector<float> x = {0, 1, 2, 3, 4, 5, 6}, y(11);
  nn::upsample_nearest(nn::ConstTensorView(x.data(), is), nn::TensorView{y.data(), os}, 1.0, 1.7);
  for (int i = 0; i < 11; ++i) EXPECT_EQ(y[i], want[i]) << i;
}

// Input [1, 2, 3, 4] (NCHW) = ((arange(24) * 0.37 - 1.1) ** 2), listed here in NHWC.
const std::vector<float> kBilinearIn = {
    1.21000004f, 11.1556005f, 0.532900035f, 13.7641001f, 0.129600003f, 16.6464024f,
    9.99998083e-05f, 19.8025017f, 0.144400001f, 23.2324009f, 0.5625f, 26.9361f,
    1.25440001f, 30.913599f, 2.2201004f, 35.1649017f, 3.45959997f, 39.6900024f,
    4.97289991f, 44.4888992f, 6.75999928f, 49.5616074f, 8.82090187f, 54.9081039f};

TEST(Resize, BilinearMatchesPyTorchBitwise) {
  // F.interpolate(x, size=(5, 7), mode='bilinear', align_corners=False), NHWC order.
  const std::vector<float> want = {
      1.21000004f, 11.1556005f, 0.96817857f, 12.0872068f, 0.581264317f, 13.5777788f,
      0.331249982f, 15.2052517f, 0.120349996f, 16.8718395f, 0.0463499799f, 18.6753235f,
      9.99998083e-05f, 19.8025017f, 0.783760011f, 15.9863214f, 0.698395669f, 17.0743847f,
      0.561812878f, 18.8152885f, 0.562130034f, 20.6930923f, 0.601561606f, 22.6100101f,
      0.777893126f, 24.663826f, 0.888100266f, 25.9474621f, 0.144400194f, 23.2324028f,
      0.293721646f, 24.5551529f, 0.532635987f, 26.6715527f, 0.908450425f, 28.9248524f,
      1.32337916f, 31.2172661f, 1.87520802f, 33.6465797f, 2.22010088f, 35.1649017f,
      2.13352036f, 33.1069641f, 2.51752758f, 34.6643982f, 3.13193893f, 37.1562958f,
      3.88325024f, 39.7850952f, 4.67367601f, 42.4530067f, 5.60100317f, 45.2578201f,
      6.18058205f, 47.0108223f, 3.45959997f, 39.6900024f, 4.00006437f, 41.4038925f,
      4.86480713f, 44.146122f, 5.86644983f, 47.0252533f, 6.90720701f, 49.9435005f,
      8.08486557f, 52.998642f, 8.82090187f, 54.9081039f};
  for (nn::Isa isa : nntest::supported_isas()) {
    nntest::IsaScope scope(isa);
    std::vector<float> y(want.size());
    nn::resize_bilinear(nn::ConstTensorView(kBilinearIn.data(), Shape{1, 3, 4, 2}),
                        nn::TensorView{y.data(), Shape{1, 5, 7, 2}});
    for (std::size_t i = 0; i < y.size(); ++i) EXPECT_EQ(y[i], want[i]) << nn::isa_name(isa) << " " << i;
  }
}

TEST(Resize, BilinearWithScaleFactorMatchesPyTorchBitwise) {
  // F.interpolate(x, scale_factor=1.7, mode='bilinear', align_corners=False,
  //               recompute_scale_factor=False) -> [1, 2, 5, 6].
  const std::vector<float> want = {
      1.21000004f, 11.1556005f, 0.951108873f, 12.1529684f, 0.552814722f, 13.6873798f,
      0.307526469f, 15.3747988f, 0.110555865f, 17.1105347f, 0.0343794003f, 18.9670639f,
      0.80256474f, 15.773201f, 0.703785002f, 16.9306812f, 0.551816165f, 18.7114162f,
      0.552853167f, 20.6451607f, 0.602207899f, 22.6272221f, 0.772356808f, 24.7300777f,
      0.175741091f, 22.8772011f, 0.323286653f, 24.2810059f, 0.550279856f, 26.4407043f,
      0.930278838f, 28.7534084f, 1.35859561f, 31.1144314f, 1.90770662f, 33.5962524f,
      1.99701202f, 32.4292984f, 2.39088273f, 34.0794258f, 2.99683785f, 36.618084f,
      3.75579858f, 39.3097534f, 4.56307745f, 42.0497398f, 5.49115086f, 44.9105186f,
      3.45959997f, 39.6900024f, 4.03821468f, 41.5248756f, 4.92839146f, 44.3477554f,
      5.97157335f, 47.3236504f, 7.06307316f, 50.3478546f, 8.27536869f, 53.4928551f};
  std::vector<float> y(want.size());
  nn::resize_bilinear(nn::ConstTensorView(kBilinearIn.data(), Shape{1, 3, 4, 2}),
                      nn::TensorView{y.data(), Shape{1, 5, 6, 2}}, 1.7, 1.7);
  for (std::size_t i = 0; i < y.size(); ++i) EXPECT_EQ(y[i], want[i]) << i;
}

// Scalar (std::fma) and AVX2 paths do the same fused operations: same bits, for
// channel counts with and without a vector tail, and for 1 or 2 threads.
TEST(Resize, BilinearPathsAndThreadCountsAgreeBitwise) {
  std::mt19937 gen(3);
  std::uniform_real_distribution<float> dist(-5.0f, 5.0f);
  for (int c : {1, 3, 8, 13, 64}) {
    const Shape is{2, 23, 37, c}, os{2, 50, 81, c};
    std::vector<float> x(is.count());
    for (auto& v : x) v = dist(gen);
    std::vector<std::vector<float>> outs;
    for (nn::Isa isa : nntest::supported_isas())
      for (int threads : {1, 2}) {
        nntest::IsaScope scope(isa);
        const int saved = nn::num_threads();
        nn::set_num_threads(threads);
        outs.emplace_back(os.count());
        nn::resize_bilinear(nn::ConstTensorView(x.data(), is), nn::TensorView{outs.back().data(), os});
        nn::set_num_threads(saved);
      }
    for (std::size_t k = 1; k < outs.size(); ++k)
      EXPECT_EQ(0, std::memcmp(outs[0].data(), outs[k].data(), outs[0].size() * sizeof(float)))
          << "c " << c << " variant " << k;
    // Same size: a copy.
    std::vector<float> same(is.count());
    nn::resize_bilinear(nn::ConstTensorView(x.data(), is), nn::TensorView{same.data(), is});
    EXPECT_EQ(0, std::memcmp(same.data(), x.data(), x.size() * sizeof(float))) << "c " << c;
  }
}

TEST(Resize, BadArgumentsThrow) {
  std::vector<float> x(2 * 3 * 4 * 5), y(2 * 6 * 8 * 5);
  const Shape is{2, 3, 4, 5};
  EXPECT_THROW(nn::upsample_nearest(nn::ConstTensorView(x.data(), is),
                                    nn::TensorView{y.data(), Shape{2, 6, 8, 4}}),
               nn::Error);
  EXPECT_THROW(nn::resize_bilinear(nn::ConstTensorView(x.data(), is),
                                   nn::TensorView{y.data(), Shape{1, 6, 8, 5}}),
               nn::Error);
  EXPECT_THROW(nn::resize_bilinear(nn::ConstTensorView(x.data(), is),
                                   nn::TensorView{y.data(), Shape{2, 0, 8, 5}}),
               nn::Error);
  EXPECT_THROW(nn::resize_bilinear(nn::ConstTensorView(x.data(), is),
                                   nn::TensorView{y.data(), Shape{2, 6, 8, 5}}, -1.0, 2.0),
               nn::Error);
  EXPECT_THROW(nn::upsample_nearest(nn::ConstTensorView(x.data(), is),
                                    nn::TensorView{x.data(), Shape{2, 3, 4, 5}}),
               nn::Error);
  EXPECT_THROW(nn::upsample_nearest(nn::ConstTensorView(nullptr, is),
                                    nn::TensorView{y.data(), Shape{2, 6, 8, 5}}),
               nn::Error);
}

}  // namespace
