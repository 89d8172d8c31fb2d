// scale_channels: every element times its image's channel scale, the same bits for
// any thread count, channel counts above and below the chunking's row width.
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "nn/channel_scale.h"
#include "nn/error.h"
#include "nn/threads.h"

namespace {

TEST(ScaleChannels, MultipliesEachPixelByItsImagesScales) {
  std::mt19937 gen(3);
  std::uniform_real_distribution<float> dist(-2.0f, 2.0f);
  for (const nn::Shape s : {nn::Shape{2, 37, 29, 72}, nn::Shape{1, 3, 5, 5000}, nn::Shape{3, 1, 1, 7}}) {
    std::vector<float> x(s.count()), scale(static_cast<std::size_t>(s.n) * s.c);
    for (auto& v : x) v = dist(gen);
    for (auto& v : scale) v = dist(gen);
    for (int threads : {1, 2}) {
      std::vector<float> y = x;
      nn::set_num_threads(threads);
      nn::scale_channels(nn::TensorView{y.data(), s}, scale.data());
      nn::set_num_threads(0);
      for (std::size_t i = 0; i < y.size(); ++i) {
        const std::size_t pixel = i / s.c, image = pixel / (static_cast<std::size_t>(s.h) * s.w);
        ASSERT_EQ(y[i], x[i] * scale[image * s.c + i % s.c]) << "element " << i << ", " << threads << " threads";
      }
    }
  }
  EXPECT_THROW(nn::scale_channels(nn::TensorView{nullptr, nn::Shape{1, 1, 1, 1}}, std::vector<float>(1).data()), nn::Error);
}

}  // namespace
