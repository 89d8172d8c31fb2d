#include "nn/threads.h"
#include "nn/channel_scale.h"

#include <cstddef>

#include "nn/error.h"

namespace nn {

void scale_channels(const TensorView& x, const float* scale) {
  if (!x.data || !scale) throw Error("scale_channels: null data");
  const int c = x.shape.c;
  const long long pixels = static_cast<long long>(x.pixels());
  // Per image: pixel p of image n uses scale row n; rows of 4096 floats per chunk.
  const long long per_image = static_cast<long long>(x.shape.h) * x.shape.w;
  const long long chunk = c >= 4096 ? 1 : 4096 / c;
  const long long chunks = (pixels + chunk - 1) / chunk;
  parallel_for(chunks, x.count() > 65536, [&](long long i_) {
    const long long i = static_cast<long long>(i_);
    const long long p1 = pixels < (i + 1) * chunk ? pixels : (i + 1) * chunk;
    for (long long p = i * chunk; p < p1; ++p) {
      float* row = x.data + static_cast<std::size_t>(p) * c;
      const float* s = scale + static_cast<std::size_t>(p / per_image) * c;
      for (int ch = 0; ch < c; ++ch) row[ch] *= s[ch];
    }
  });
}

}  // namespace nn
