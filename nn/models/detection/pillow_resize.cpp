#include "nn/models/detection/pillow_resize.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "nn/threads.h"

namespace nn::detection {

namespace {

constexpr int kPrecisionBits = 32 - 8 - 2;

double bilinear(double x) {
  if (x < 0.0) x = -x;
  return x < 1.0 ? 1.0 - x : 0.0;
}

// clip8: the fixed-point sum back to a byte.
std::uint8_t clip8(std::int32_t v) {
  if (v >= (1 << kPrecisionBits << 8)) return 255;
  if (v <= 0) return 0;
  return static_cast<std::uint8_t>(v >> kPrecisionBits);
}

}  // namespace

PillowAxis pillow_bilinear_axis(int in, int out) {
  PillowAxis a;
  a.in = in, a.out = out;
  const double scale = static_cast<double>(in) / out;
  const double filterscale = std::max(scale, 1.0);
  const double support = 1.0 * filterscale;  // the bilinear filter's support is 1
  a.ksize = static_cast<int>(std::ceil(support)) * 2 + 1;
  a.first.resize(out), a.count.resize(out);
  a.k.assign(static_cast<std::size_t>(out) * a.ksize, 0);
  std::vector<double> w(a.ksize);
  for (int i = 0; i < out; ++i) {
    const double center = (i + 0.5) * scale;
    const double ss = 1.0 / filterscale;
    int xmin = static_cast<int>(center - support + 0.5);
    if (xmin < 0) xmin = 0;
    int xmax = static_cast<int>(center + support + 0.5);
    if (xmax > in) xmax = in;
    xmax -= xmin;
    double ww = 0.0;
    for (int x = 0; x < xmax; ++x) {
      w[x] = bilinear((x + xmin - center + 0.5) * ss);
      ww += w[x];
    }
    for (int x = 0; x < xmax; ++x) {
      const double v = ww != 0.0 ? w[x] / ww : w[x];
      // C truncation of +-0.5 + v * 2^22, as normalize_coeffs_8bpc.
      a.k[static_cast<std::size_t>(i) * a.ksize + x] =
          static_cast<std::int32_t>(v < 0 ? -0.5 + v * (1 << kPrecisionBits) : 0.5 + v * (1 << kPrecisionBits));
    }
    a.first[i] = xmin, a.count[i] = xmax;
  }
  return a;
}

void PillowResize::plan(int in_h, int in_w, int out_h, int out_w) {
  h_ = pillow_bilinear_axis(in_w, out_w);
  v_ = pillow_bilinear_axis(in_h, out_h);
  // Only the rows some output row reads go through the horizontal pass.
  row_first_ = v_.first[0];
  row_count_ = v_.first[out_h - 1] + v_.count[out_h - 1] - row_first_;
  tmp_.resize(static_cast<std::size_t>(row_count_) * out_w * 3);
}

void PillowResize::run(const std::uint8_t* src, std::uint8_t* dst) {
  const bool need_h = h_.in != h_.out, need_v = v_.in != v_.out;
  const int in_w = h_.in, out_w = h_.out, out_h = v_.out;
  if (!need_h && !need_v) {
    std::memcpy(dst, src, static_cast<std::size_t>(out_h) * out_w * 3);
    return;
  }
  const std::int32_t half = 1 << (kPrecisionBits - 1);
  // Horizontal pass (into dst directly when there is no vertical one).
  const std::uint8_t* rows = src;  // the vertical pass's input, row 0 = source row `base`
  int base = 0;
  if (need_h) {
    std::uint8_t* hout = need_v ? tmp_.data() : dst;
    const int first = need_v ? row_first_ : 0, count = need_v ? row_count_ : out_h;
    parallel_for(count, static_cast<long long>(count) * out_w > 16384, [&](long long r) {
      const std::uint8_t* in = src + static_cast<std::size_t>(first + r) * in_w * 3;
      std::uint8_t* o = hout + static_cast<std::size_t>(r) * out_w * 3;
      for (int x = 0; x < out_w; ++x) {
        const std::int32_t* k = &h_.k[static_cast<std::size_t>(x) * h_.ksize];
        const std::uint8_t* p = in + static_cast<std::size_t>(h_.first[x]) * 3;
        std::int32_t s0 = half, s1 = half, s2 = half;
        for (int t = 0; t < h_.count[x]; ++t) {
          s0 += p[3 * t] * k[t], s1 += p[3 * t + 1] * k[t], s2 += p[3 * t + 2] * k[t];
        }
        o[3 * x] = clip8(s0), o[3 * x + 1] = clip8(s1), o[3 * x + 2] = clip8(s2);
      }
    });
    if (!need_v) return;
    rows = tmp_.data(), base = row_first_;
  }
  const std::size_t stride = static_cast<std::size_t>(out_w) * 3;
  parallel_for(out_h, static_cast<long long>(out_h) * out_w > 16384, [&](long long y) {
    const std::int32_t* k = &v_.k[static_cast<std::size_t>(y) * v_.ksize];
    const std::uint8_t* in = rows + static_cast<std::size_t>(v_.first[y] - base) * stride;
    std::uint8_t* o = dst + static_cast<std::size_t>(y) * stride;
    const int taps = v_.count[y];
    for (std::size_t x = 0; x < stride; ++x) {
      std::int32_t s = half;
      for (int t = 0; t < taps; ++t) s += in[t * stride + x] * k[t];
      o[x] = clip8(s);
    }
  });
}

}  // namespace nn::detection
