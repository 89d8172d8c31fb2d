#include "nn/threads.h"
#include "nn/resize.h"

#include <cmath>
#include <cstring>
#include <string>

#include "nn/error.h"
#include "nn/isa.h"
#include "nn/kernel_table.h"
#include "nn/resize_kernel.h"

namespace nn {
namespace {

void check(const char* who, const ConstTensorView& in, const TensorView& out, double scale_h,
           double scale_w) {
  const Shape& a = in.shape;
  const Shape& b = out.shape;
  if (a.n < 1 || a.h < 1 || a.w < 1 || a.c < 1 || b.h < 1 || b.w < 1 || a.n != b.n || a.c != b.c)
    throw Error(std::string(who) + ": cannot resize " + shape_str(a) + " to " + shape_str(b) +
                " (sizes must be positive, batch and channels equal)");
  if (!(scale_h >= 0.0) || !(scale_w >= 0.0) || std::isinf(scale_h) || std::isinf(scale_w))
    throw Error(std::string(who) + ": scale factors must be finite and positive (or 0 for none)");
  if (!in.data || !out.data) throw Error(std::string(who) + ": null tensor data");
  if (in.data < out.data + out.count() && out.data < in.data + in.count())
    throw Error(std::string(who) + ": output must not overlap the input");
}

// compute_scales_value<float>: the factor PyTorch was given wins over the sizes.
float axis_scale(long long in, long long out, double scale) {
  return scale > 0.0 ? static_cast<float>(1.0 / scale)
                     : static_cast<float>(in) / static_cast<float>(out);
}

long long nearest_src(long long dst, long long in, long long out, float s) {
  if (out == in) return dst;
  if (out == 2 * in) return dst >> 1;
  const long long i = static_cast<long long>(std::floor(static_cast<float>(dst) * s));
  return i < in - 1 ? i : in - 1;
}

struct Lerp {
  long long i0, i1;
  float l0, l1;
};

// compute_source_index_and_lambda<float>: the source position is computed in
// double (PyTorch's acc_type<float> on CPU), the weights rounded to float.
Lerp linear_src(long long dst, long long in, long long out, float ratio) {
  if (out == in) return Lerp{dst, dst, 1.0f, 0.0f};
  double real = static_cast<double>(ratio) * (static_cast<double>(dst) + 0.5) - 0.5;
  if (real < 0.0) real = 0.0;
  const long long i0 = static_cast<long long>(real);
  const float l1 = static_cast<float>(real - static_cast<double>(i0));
  return Lerp{i0, i0 < in - 1 ? i0 + 1 : i0, 1.0f - l1, l1};
}


}  // namespace

void resize_bilinear_row_scalar(const float* row0, const float* row1, float h0, float h1,
                         const long long* x0, const long long* x1, const float* w0,
                         const float* w1, int count, int c, float* out) {
  for (int i = 0; i < count; ++i, out += c) {
    const float *a = row0 + x0[i], *b = row0 + x1[i], *p = row1 + x0[i], *q = row1 + x1[i];
    for (int ch = 0; ch < c; ++ch) {
      const float t0 = std::fma(a[ch], w0[i], b[ch] * w1[i]);
      const float t1 = std::fma(p[ch], w0[i], q[ch] * w1[i]);
      out[ch] = std::fma(t0, h0, t1 * h1);
    }
  }
}

void upsample_nearest(const ConstTensorView& in, const TensorView& out, double scale_h,
                      double scale_w) {
  check("upsample_nearest", in, out, scale_h, scale_w);
  const Shape& is = in.shape;
  const Shape& os = out.shape;
  const float sh = axis_scale(is.h, os.h, scale_h), sw = axis_scale(is.w, os.w, scale_w);
  const long long rows = static_cast<long long>(os.n) * os.h;
  const std::size_t bytes = static_cast<std::size_t>(is.c) * sizeof(float);
  parallel_for(rows, rows > 1 && out.count() > 65536, [&](long long r_) {
    const long long r = static_cast<long long>(r_);
    const int n = static_cast<int>(r / os.h), oy = static_cast<int>(r % os.h);
    const int iy = static_cast<int>(nearest_src(oy, is.h, os.h, sh));
    for (int ox = 0; ox < os.w; ++ox) {
      const int ix = static_cast<int>(nearest_src(ox, is.w, os.w, sw));
      std::memcpy(out.pixel(n, oy, ox), in.pixel(n, iy, ix), bytes);
    }
  });
}

void resize_bilinear(const ConstTensorView& in, const TensorView& out, double scale_h,
                     double scale_w) {
  check("resize_bilinear", in, out, scale_h, scale_w);
  const Shape& is = in.shape;
  const Shape& os = out.shape;
  const float sh = axis_scale(is.h, os.h, scale_h), sw = axis_scale(is.w, os.w, scale_w);
  const ResizeBilinearRowFn row_kernel = kernel_table(active_isa()).resize_bilinear_row;
  // Items: (image, chunk of output rows). The column taps of a 128-pixel segment
  // are computed once per item on the stack (no allocation) and reused by its rows.
  constexpr int kChunk = 8, kSeg = 128;
  const long long chunks = (os.h + kChunk - 1) / kChunk;
  const long long items = os.n * chunks;
  parallel_for(items, items > 1 && out.count() > 65536, [&](long long it_) {
    const long long it = static_cast<long long>(it_);
    const int n = static_cast<int>(it / chunks);
    const int oy0 = static_cast<int>(it % chunks) * kChunk;
    const int oy1 = oy0 + kChunk < os.h ? oy0 + kChunk : os.h;
    long long x0[kSeg], x1[kSeg];
    float w0[kSeg], w1[kSeg];
    for (int ox0 = 0; ox0 < os.w; ox0 += kSeg) {
      const int count = os.w - ox0 < kSeg ? os.w - ox0 : kSeg;
      for (int i = 0; i < count; ++i) {
        const Lerp x = linear_src(ox0 + i, is.w, os.w, sw);
        x0[i] = x.i0 * is.c;
        x1[i] = x.i1 * is.c;
        w0[i] = x.l0;
        w1[i] = x.l1;
      }
      for (int oy = oy0; oy < oy1; ++oy) {
        const Lerp y = linear_src(oy, is.h, os.h, sh);
        const float* row0 = in.pixel(n, static_cast<int>(y.i0), 0);
        const float* row1 = in.pixel(n, static_cast<int>(y.i1), 0);
        float* dst = out.pixel(n, oy, ox0);
        row_kernel(row0, row1, y.l0, y.l1, x0, x1, w0, w1, count, is.c, dst);
      }
    }
  });
}

}  // namespace nn
