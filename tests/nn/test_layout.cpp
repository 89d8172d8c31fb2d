// NCHW <-> NHWC transposes against index arithmetic, round trips, errors.
#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "nn/error.h"
#include "nn/layout.h"
#include "nn/threads.h"

namespace {

TEST(Layout, TransposesMatchIndexArithmeticAndRoundTrip) {
  struct Dims { int n, c, h, w; };
  for (const Dims& d : {Dims{1, 1, 1, 1}, Dims{2, 3, 5, 7}, Dims{1, 17, 33, 31}, Dims{3, 64, 9, 40},
                        Dims{1, 100, 1, 61}, Dims{2, 3, 120, 160}}) {
    const std::size_t count = static_cast<std::size_t>(d.n) * d.c * d.h * d.w;
    std::vector<float> nchw(count);
    for (std::size_t i = 0; i < count; ++i) nchw[i] = static_cast<float>(i);
    for (int threads : {1, 2}) {
      const int saved = nn::num_threads();
      nn::set_num_threads(threads);
      std::vector<float> nhwc(count, -1.0f), back(count, -1.0f);
      nn::nchw_to_nhwc(nchw.data(), d.n, d.c, d.h, d.w, nhwc.data());
      nn::nhwc_to_nchw(nhwc.data(), d.n, d.c, d.h, d.w, back.data());
      nn::set_num_threads(saved);
      for (int n = 0; n < d.n; ++n)
        for (int c = 0; c < d.c; ++c)
          for (int y = 0; y < d.h; ++y)
            for (int x = 0; x < d.w; ++x)
              ASSERT_EQ(nhwc[((static_cast<std::size_t>(n) * d.h + y) * d.w + x) * d.c + c],
                        nchw[((static_cast<std::size_t>(n) * d.c + c) * d.h + y) * d.w + x]);
      EXPECT_EQ(0, std::memcmp(back.data(), nchw.data(), count * sizeof(float)));
    }
  }
}

TEST(Layout, BadArgumentsThrowAndEmptyIsANoOp) {
  std::vector<float> a(24), b(24);
  EXPECT_THROW(nn::nchw_to_nhwc(a.data(), 1, -2, 3, 4, b.data()), nn::Error);
  EXPECT_THROW(nn::nhwc_to_nchw(a.data(), 1, 2, 3, 4, a.data() + 4), nn::Error);
  EXPECT_THROW(nn::nchw_to_nhwc(nullptr, 1, 2, 3, 4, b.data()), nn::Error);
  EXPECT_NO_THROW(nn::nchw_to_nhwc(nullptr, 0, 2, 3, 4, nullptr));
}

}  // namespace
