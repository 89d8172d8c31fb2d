// Float arithmetic here is written operation by operation in OpenCV's order and
// precision (the project builds with -ffp-contract=off, so nothing is fused).
#include "shle/mil_haar.h"

#include <cmath>
#include <cstdint>

#include "nn/cpu_features.h"

namespace shle {

void mil_integral(const GrayView& img, int lanes, int channels, MilIntegral* out) {
  out->width = img.width;
  out->height = img.height;
  const std::size_t s = out->stride();
  out->sum.assign(s * (static_cast<std::size_t>(img.height) + 1), 0.0f);
  const int w = img.width;
  for (int i = 0; i < img.height; ++i) {
    const std::uint8_t* src = img.data + static_cast<std::size_t>(i) * w;
    const float* above = out->sum.data() + static_cast<std::size_t>(i) * s + 1;
    float* row = out->sum.data() + static_cast<std::size_t>(i + 1) * s + 1;
    int j = 0;
    if (lanes > 0) {
      // The 3-channel loop deinterleaves 2 * lanes pixels at a time, so on rows
      // near the end of the buffer it needs that many left to start a block.
      int need = lanes;
      const std::size_t step = static_cast<std::size_t>(w) * 3;
      if (channels == 3 && step * i + step + static_cast<std::size_t>(lanes) * 3 >= step * img.height) need = 2 * lanes;
      // Whole blocks: the running row sum is an exact integer (below 2^24 for
      // any width the tracker accepts), added once to the value above.
      std::int64_t prefix = 0;
      for (; j + need <= w; j += lanes)
        for (int k = j; k < j + lanes; ++k) {
          prefix += src[k];
          row[k] = static_cast<float>(prefix) + above[k];
        }
    }
    // The rest continues from the prefix as recovered from the stored sums.
    float v = j > 0 ? row[j - 1] - above[j - 1] : 0.0f;
    for (; j < w; ++j) {
      v += static_cast<float>(src[j]);
      row[j] = v + above[j];
    }
  }
}

int opencv_integral_lanes() {
  // OpenCV's own dispatch (not our kernel cap) decides, so the CPU's features do:
  // its AVX512_SKX level needs F, CD, BW, DQ and VL; its AVX2 level AVX2; otherwise
  // 128-bit vectors (SSE2, NEON and others).
  const nn::CpuFeatures& f = nn::cpu_features();
  if (f.avx512f && f.avx512cd && f.avx512bw && f.avx512dq && f.avx512vl) return 32;
  if (f.avx2) return 16;
  return 8;
}

bool draw_haar_feature(int w, int h, GlibcRand* rand, HaarFeature* out, long max_attempts) {
  if (w <= 0 || h <= 0) return false;
  const float inv_rand_max = static_cast<float>(1.0 / 2147483647.0);
  // Cumulative type probabilities, summed in float as OpenCV's comparisons do;
  // only the first six types have a non-zero probability.
  const float p = 0.2f;
  float cum[6];
  cum[0] = p;
  for (int k = 1; k < 6; ++k) cum[k] = cum[k - 1] + p;
  // Size factors (height, width) of the whole feature per type.
  static const int fh[6] = {2, 1, 4, 1, 2, 3}, fw[6] = {1, 2, 1, 4, 2, 3};
  // Can any type fit at all (at x = y = 0 with the largest base size)? If not,
  // OpenCV would draw forever; fail before drawing.
  bool possible = false;
  for (int t = 0; t < 6; ++t) {
    const long bw = (w - 1) / fw[t], bh = (h - 1) / fh[t];
    possible = possible || (bw >= 1 && bh >= 1 && bw * fw[t] * bh * fh[t] >= 9);
  }
  if (!possible) return false;
  for (long attempt = 0; attempt < max_attempts; ++attempt) {
    const int y = rand->next() % h;
    const int x = rand->next() % w;
    const float u1 = static_cast<float>(rand->next()) * inv_rand_max;
    const int bw = static_cast<int>((1.0f - std::sqrt(1.0f - u1)) * static_cast<float>(w));
    const float u2 = static_cast<float>(rand->next()) * inv_rand_max;
    const int bh = static_cast<int>((1.0f - std::sqrt(1.0f - u2)) * static_cast<float>(h));
    const float prob = static_cast<float>(rand->next()) * inv_rand_max;
    int type = 0;
    while (type < 6 && !(prob < cum[type])) ++type;
    if (type == 6) continue;  // unreachable: prob <= 1 < cum[5]
    if (y + bh * fh[type] >= h || x + bw * fw[type] >= w) continue;
    if (bh * fh[type] * bw * fw[type] < 9) continue;
    HaarFeature f;
    auto put = [&f](int ax, int ay, int aw, int ah, float weight) {
      f.areas[f.count++] = HaarFeature::Area{ax, ay, aw, ah, weight};
    };
    switch (type) {
      case 0:  // two stacked
        put(x, y, bw, bh, 1);
        put(x, y + bh, bw, bh, -1);
        break;
      case 1:  // two side by side
        put(x, y, bw, bh, 1);
        put(x + bw, y, bw, bh, -1);
        break;
      case 2:  // three stacked, double-height middle
        put(x, y, bw, bh, 1);
        put(x, y + bh, bw, 2 * bh, -2);
        put(x, y + 3 * bh, bw, bh, 1);
        break;
      case 3:  // three side by side, double-width middle
        put(x, y, bw, bh, 1);
        put(x + bw, y, 2 * bw, bh, -2);
        put(x + 3 * bw, y, bw, bh, 1);
        break;
      case 4:  // checkerboard
        put(x, y, bw, bh, 1);
        put(x + bw, y, bw, bh, -1);
        put(x, y + bh, bw, bh, -1);
        put(x + bw, y + bh, bw, bh, 1);
        break;
      default:  // centre-surround: 3x3 block minus 9 times its centre
        put(x, y, 3 * bw, 3 * bh, 1);
        put(x + bw, y + bh, bw, bh, -9);
    }
    for (int a = 0; a < f.count; ++a)
      f.areas[a].weight = f.areas[a].weight / static_cast<float>(f.areas[a].w * f.areas[a].h);
    *out = f;
    return true;
  }
  return false;
}

float haar_value(const HaarFeature& f, const MilIntegral& ii, int x, int y, int w, int h) {
  const std::size_t s = ii.stride();
  const float* base = ii.sum.data() + static_cast<std::size_t>(y) * s + x;
  auto at = [base, s](int r, int c) { return base[static_cast<std::size_t>(r) * s + c]; };
  float result = 0.0f;
  for (int a = 0; a < f.count; ++a) {
    const HaarFeature::Area& q = f.areas[a];
    int qw = q.w, qh = q.h;
    if (q.x + qw >= w - 1) qw = (w - 1) - q.x;
    if (q.y + qh >= h - 1) qh = (h - 1) - q.y;
    const float sum = at(q.y + qh, q.x + qw) + at(q.y, q.x) - at(q.y, q.x + qw) - at(q.y + qh, q.x);
    result += sum * q.weight;
  }
  return result;
}

}  // namespace shle
