#include "nn/threads.h"
#include "nn/pool.h"

#include <cstddef>
#include <limits>
#include <string>

#include "nn/error.h"

namespace nn {
namespace {

void check_io(const char* who, const ConstTensorView& in, const TensorView& out,
              const Shape& want) {
  if (out.shape != want)
    throw Error(std::string(who) + ": output shape " + shape_str(out.shape) + " should be " + shape_str(want));
  if (!in.data || !out.data) throw Error(std::string(who) + ": null tensor data");
  if (in.data < out.data + out.count() && out.data < in.data + in.count())
    throw Error(std::string(who) + ": output must not overlap the input");
}

void check_input(const char* who, const Shape& in) {
  if (in.n < 1 || in.h < 1 || in.w < 1 || in.c < 1)
    throw Error(std::string(who) + ": input shape " + shape_str(in) + " must be positive");
}

}  // namespace

Shape mean_over_rows_shape(const Shape& in) {
  check_input("mean_over_rows", in);
  return Shape{in.n, 1, in.w, in.c};
}

void mean_over_rows(const ConstTensorView& in, const TensorView& out) {
  check_io("mean_over_rows", in, out, mean_over_rows_shape(in.shape));
  const Shape& s = in.shape;
  const long long row = static_cast<long long>(s.w) * s.c;
  // Items: (image, 1024-float slice of a row); each element summed by one thread.
  constexpr long long kSlice = 1024;
  const long long slices = (row + kSlice - 1) / kSlice;
  const long long items = s.n * slices;
  const float h = static_cast<float>(s.h);
  parallel_for(items, items > 1 && s.count() > 65536, [&](long long it_) {
    const long long it = static_cast<long long>(it_);
    const long long n = it / slices;
    const long long b = it % slices * kSlice;
    const long long e = b + kSlice < row ? b + kSlice : row;
    const float* src = in.data + n * s.h * row;
    float* dst = out.data + n * row;
    for (long long i = b; i < e; ++i) dst[i] = 0.0f;
    for (int y = 0; y < s.h; ++y)
      for (long long i = b; i < e; ++i) dst[i] += src[y * row + i];
    for (long long i = b; i < e; ++i) dst[i] /= h;
  });
}

Shape max_pool2d_output_shape(const Shape& in, const MaxPoolParams& p) {
  check_input("max_pool2d", in);
  // Built only on the error paths: forward passes must not allocate.
  auto k = [&p] {
    return std::to_string(p.kh) + "x" + std::to_string(p.kw) + " stride " + std::to_string(p.stride_h) + "," +
           std::to_string(p.stride_w) + " pad " + std::to_string(p.pad_h) + "," + std::to_string(p.pad_w);
  };
  if (p.kh < 1 || p.kw < 1 || p.stride_h < 1 || p.stride_w < 1 || p.pad_h < 0 || p.pad_w < 0)
    throw Error("max_pool2d: kernel " + k() + ": sizes and strides must be positive, pads >= 0");
  if (2 * p.pad_h > p.kh || 2 * p.pad_w > p.kw)
    throw Error("max_pool2d: kernel " + k() + ": pad should be at most half of the kernel size");
  const int eh = in.h + 2 * p.pad_h - p.kh, ew = in.w + 2 * p.pad_w - p.kw;
  if (eh < 0 || ew < 0)
    throw Error("max_pool2d: input " + shape_str(in) + " is smaller than kernel " + k());
  return Shape{in.n, eh / p.stride_h + 1, ew / p.stride_w + 1, in.c};
}

void max_pool2d(const ConstTensorView& in, const MaxPoolParams& p, const TensorView& out) {
  check_io("max_pool2d", in, out, max_pool2d_output_shape(in.shape, p));
  const Shape& s = in.shape;
  const Shape& os = out.shape;
  const long long rows = static_cast<long long>(os.n) * os.h;
  parallel_for(rows, rows > 1 && out.count() > 16384, [&](long long r_) {
    const long long r = static_cast<long long>(r_);
    const int n = static_cast<int>(r / os.h), oy = static_cast<int>(r % os.h);
    const int y0 = oy * p.stride_h - p.pad_h;
    const int ya = y0 < 0 ? 0 : y0;
    const int yb = y0 + p.kh < s.h ? y0 + p.kh : s.h;
    for (int ox = 0; ox < os.w; ++ox) {
      const int x0 = ox * p.stride_w - p.pad_w;
      const int xa = x0 < 0 ? 0 : x0;
      const int xb = x0 + p.kw < s.w ? x0 + p.kw : s.w;
      float* dst = out.pixel(n, oy, ox);
      // Channels in chunks held in a local array, so the compiler sees no aliasing
      // and vectorises the compare-select.
      constexpr int kChunk = 64;
      for (int c0 = 0; c0 < s.c; c0 += kChunk) {
        const int cn = s.c - c0 < kChunk ? s.c - c0 : kChunk;
        float m[kChunk];
        for (int i = 0; i < cn; ++i) m[i] = -std::numeric_limits<float>::infinity();
        for (int y = ya; y < yb; ++y)
          for (int x = xa; x < xb; ++x) {
            const float* src = in.pixel(n, y, x) + c0;
            for (int i = 0; i < cn; ++i) {
              const float v = src[i];
              // PyTorch's test: take v if larger or NaN, so NaN sticks.
              m[i] = (v > m[i] || v != v) ? v : m[i];
            }
          }
        for (int i = 0; i < cn; ++i) dst[c0 + i] = m[i];
      }
    }
  });
}

Shape global_avg_pool_shape(const Shape& in) {
  check_input("global_avg_pool", in);
  return Shape{in.n, 1, 1, in.c};
}

void global_avg_pool(const ConstTensorView& in, const TensorView& out) {
  check_io("global_avg_pool", in, out, global_avg_pool_shape(in.shape));
  const Shape& s = in.shape;
  // Channels in slices of kSlice; the pixels of an image in kParts fixed ranges summed
  // in parallel, then the partial sums in range order: the bits do not depend on the
  // thread count, and all of the team works however few channels there are. Up to
  // kGroup slices (1024 channels: every SE block of MobileNetV3) share one parallel
  // region, a task per (slice, range): each region is a barrier, and on a loaded host a
  // barrier can wait for a thread the scheduler has put off the CPU.
  constexpr int kSlice = 256, kParts = 8, kGroup = 4;
  const long long pixels = static_cast<long long>(s.h) * s.w;
  for (int n = 0; n < s.n; ++n)
    for (int g0 = 0; g0 < s.c; g0 += kGroup * kSlice) {
      const int gc = s.c - g0 < kGroup * kSlice ? s.c - g0 : kGroup * kSlice;
      const int slices = (gc + kSlice - 1) / kSlice;  // the last one may be partial
      double partial[kGroup][kParts][kSlice];
      const float* src = in.data + n * pixels * s.c + g0;
      parallel_for(static_cast<long long>(slices) * kParts, pixels * gc > 65536, [&](long long task) {
        const int slice = static_cast<int>(task / kParts), part = static_cast<int>(task % kParts);
        const int c0 = slice * kSlice;
        const int cn = gc - c0 < kSlice ? gc - c0 : kSlice;
        double* acc = partial[slice][part];
        for (int i = 0; i < cn; ++i) acc[i] = 0.0;
        const long long p1 = pixels * (part + 1) / kParts;
        for (long long px = pixels * part / kParts; px < p1; ++px)
          for (int i = 0; i < cn; ++i) acc[i] += src[px * s.c + c0 + i];
      });
      float* dst = out.data + static_cast<std::size_t>(n) * s.c + g0;
      for (int i = 0; i < gc; ++i) {
        double sum = 0.0;
        for (int part = 0; part < kParts; ++part) sum += partial[i / kSlice][part][i % kSlice];
        dst[i] = static_cast<float>(sum / static_cast<double>(pixels));
      }
    }
}

}  // namespace nn
