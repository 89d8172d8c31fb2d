#include "nn/threads.h"
#include "nn/dwconv.h"

#include <algorithm>
#include <cstddef>
#include <string>

#include "nn/dwconv_kernel.h"
#include "nn/kernel_table.h"
#include "nn/error.h"

namespace nn {
namespace {

// Channels per packed vector; 0 for the scalar path, which keeps whole rows of taps.
int lanes_of(Isa isa) {
  const KernelTable& k = kernel_table(isa);
  return k.dwconv_block ? k.lanes : 0;
}

std::string describe(const DwConvParams& p) {
  return std::to_string(p.kh) + "x" + std::to_string(p.kw) + " stride " +
         std::to_string(p.stride_h) + "," + std::to_string(p.stride_w) + " pad " +
         std::to_string(p.pad_h) + "," + std::to_string(p.pad_w);
}

void check_params(const DwConvParams& p) {
  if (p.kh < 1 || p.kw < 1 || p.kh > kDwConvMaxKernel || p.kw > kDwConvMaxKernel ||
      p.kh * p.kw > kDwConvMaxTaps)
    throw Error("dwconv: kernel " + describe(p) + ": kernel sides must be 1.." +
                std::to_string(kDwConvMaxKernel) + " with at most " +
                std::to_string(kDwConvMaxTaps) + " taps");
  if (p.stride_h < 1 || p.stride_w < 1 || p.stride_h > 64 || p.stride_w > 64)
    throw Error("dwconv: kernel " + describe(p) + ": stride must be 1..64");
  if (p.pad_h < 0 || p.pad_w < 0 || p.pad_h > 4096 || p.pad_w > 4096)
    throw Error("dwconv: kernel " + describe(p) + ": padding must be 0..4096");
}

void check_act(Act act) {
  if (act != Act::None && act != Act::Relu && act != Act::HardSwish)
    throw Error(
        "dwconv: only None, Relu and HardSwish can be fused into the depthwise kernel; apply "
        "this activation separately (nn/activation.h)");
}

// The epilogue activations, written exactly as PyTorch evaluates them.
float activate(float v, Act act) {
  if (act == Act::Relu) return v < 0.0f ? 0.0f : v;  // NaN stays NaN
  if (act == Act::HardSwish) {
    float t = v + 3.0f;
    t = t < 0.0f ? 0.0f : t;
    t = t > 6.0f ? 6.0f : t;
    return v * t / 6.0f;
  }
  return v;
}

bool overlaps(const float* a, std::size_t na, const float* b, std::size_t nb) {
  return a < b + nb && b < a + na;
}

const DwConvParams& packed_params(const DwConvWeights& w) {
  if (w.channels() == 0) throw Error("dwconv: weights are not packed");
  return w.params();
}

// The input half of the checks, shared by the whole-map and the row-band entry points.
void check_input(const ConstTensorView& in, int c) {
  if (in.shape.n < 1 || in.shape.h < 1 || in.shape.w < 1 || in.shape.c < 1)
    throw Error("dwconv: input shape must be positive, got [" + std::to_string(in.shape.n) +
                "," + std::to_string(in.shape.h) + "," + std::to_string(in.shape.w) + "," +
                std::to_string(in.shape.c) + "]");
  if (in.shape.c != c)
    throw Error("dwconv: input has " + std::to_string(in.shape.c) + " channels, weights have " +
                std::to_string(c));
  if (!in.data) throw Error("dwconv: null tensor data");
}

void check_views(const ConstTensorView& in, const DwConvParams& p, int c, const TensorView& out) {
  check_input(in, c);
  const Shape want = dwconv_output_shape(in.shape, p);
  if (out.shape != want)
    throw Error("dwconv: output shape [" + std::to_string(out.shape.n) + "," +
                std::to_string(out.shape.h) + "," + std::to_string(out.shape.w) + "," +
                std::to_string(out.shape.c) + "] should be [" + std::to_string(want.n) + "," +
                std::to_string(want.h) + "," + std::to_string(want.w) + "," +
                std::to_string(want.c) + "]");
  if (!out.data) throw Error("dwconv: null tensor data");
  if (overlaps(in.data, in.count(), out.data, out.count()))
    throw Error("dwconv: output must not overlap the input");
}

// Scalar path on [kh][kw][c] taps: per output pixel, channels in chunks whose
// accumulators stay on the stack; same order as dwconv_ref, hence bitwise equal to it.
// Output row oy of image n into dst ([ow][c]).
void dwconv_row_scalar(const ConstTensorView& in, const DwConvWeights& w, int ow, int n, int oy,
                       float* dst_row) {
  const DwConvParams& p = w.params();
  const Shape& is = in.shape;
  const int c = is.c;
  constexpr int kChunk = 64;
  for (int ox = 0; ox < ow; ++ox) {
    float* dst = dst_row + static_cast<std::ptrdiff_t>(ox) * c;
    for (int c0 = 0; c0 < c; c0 += kChunk) {
      const int cn = c - c0 < kChunk ? c - c0 : kChunk;
      float acc[kChunk] = {};
      for (int ky = 0; ky < p.kh; ++ky) {
        const int iy = oy * p.stride_h - p.pad_h + ky;
        if (iy < 0 || iy >= is.h) continue;
        for (int kx = 0; kx < p.kw; ++kx) {
          const int ix = ox * p.stride_w - p.pad_w + kx;
          if (ix < 0 || ix >= is.w) continue;
          const float* x = in.pixel(n, iy, ix) + c0;
          const float* t = w.taps() + (static_cast<std::size_t>(ky) * p.kw + kx) * c + c0;
          for (int i = 0; i < cn; ++i) acc[i] += x[i] * t[i];
        }
      }
      const float* b = w.bias() + c0;
      for (int i = 0; i < cn; ++i) dst[c0 + i] = activate(acc[i] + b[i], p.act);
    }
  }
}


}  // namespace

Shape dwconv_output_shape(const Shape& in, const DwConvParams& p) {
  check_params(p);
  const int eh = in.h + 2 * p.pad_h - p.kh, ew = in.w + 2 * p.pad_w - p.kw;
  if (in.h < 1 || in.w < 1 || eh < 0 || ew < 0)
    throw Error("dwconv: input " + std::to_string(in.h) + "x" + std::to_string(in.w) +
                " is smaller than kernel " + describe(p));
  return Shape{in.n, eh / p.stride_h + 1, ew / p.stride_w + 1, in.c};
}

DwConvWeights DwConvWeights::pack(const float* w, const float* bias, int c, const DwConvParams& p,
                                  Isa isa) {
  check_params(p);
  check_act(p.act);
  if (c < 1) throw Error("dwconv: channel count must be positive, got " + std::to_string(c));
  if (!w) throw Error("dwconv: null weights");
  isa = cap_isa(isa);

  DwConvWeights out;
  out.c_ = c;
  out.p_ = p;
  out.isa_ = isa;
  const std::size_t taps = static_cast<std::size_t>(p.kh) * p.kw;
  const int lanes = lanes_of(isa);
  if (lanes == 0) {
    // [kh][kw][c]: the scalar loop runs over contiguous channels per tap.
    out.taps_.resize(taps * c);
    out.bias_.resize(c);
    for (int ch = 0; ch < c; ++ch)
      for (std::size_t t = 0; t < taps; ++t) out.taps_[t * c + ch] = w[ch * taps + t];
  } else {
    // [c/L][kh][kw][L], channel tail zero (AlignedBuffer zero-fills).
    const std::size_t blocks = (static_cast<std::size_t>(c) + lanes - 1) / lanes;
    out.taps_.resize(blocks * taps * lanes);
    out.bias_.resize(blocks * lanes);
    for (int ch = 0; ch < c; ++ch) {
      const std::size_t cb = ch / lanes, lane = ch % lanes;
      for (std::size_t t = 0; t < taps; ++t)
        out.taps_[(cb * taps + t) * lanes + lane] = w[ch * taps + t];
    }
  }
  if (bias)
    for (int ch = 0; ch < c; ++ch) out.bias_[ch] = bias[ch];
  return out;
}

namespace {

DwConvJob make_job(const ConstTensorView& in, const DwConvWeights& w, const Shape& os, float* out) {
  const DwConvParams& p = w.params();
  const Shape& is = in.shape;
  DwConvJob job;
  job.in = in.data;
  job.out = out;
  job.taps = w.taps();
  job.bias = w.bias();
  job.h = is.h;
  job.w = is.w;
  job.c = is.c;
  job.oh = os.h;
  job.ow = os.w;
  job.kh = p.kh;
  job.kw = p.kw;
  job.stride_h = p.stride_h;
  job.stride_w = p.stride_w;
  job.pad_h = p.pad_h;
  job.pad_w = p.pad_w;
  job.act = static_cast<int>(p.act);
  job.out_image = static_cast<std::ptrdiff_t>(os.h) * os.w * os.c;
  return job;
}

}  // namespace

void dwconv(const ConstTensorView& in, const DwConvWeights& w, const TensorView& out) {
  const DwConvParams& p = packed_params(w);
  check_views(in, p, w.channels(), out);
  const Shape& is = in.shape;
  const Shape& os = out.shape;
  const int threads = team_size();

  const DwConvBlockFn block = kernel_table(w.isa()).dwconv_block;
  if (!block) {
    const long long rows = static_cast<long long>(os.n) * os.h;
    parallel_for(rows, rows > 1, [&](long long r_) {
      const long long r = static_cast<long long>(r_);
      const int n = static_cast<int>(r / os.h), oy = static_cast<int>(r % os.h);
      dwconv_row_scalar(in, w, os.w, n, oy, out.pixel(n, oy, 0));
    });
    return;
  }

  const DwConvJob job = make_job(in, w, os, out.data);

  // Work items: (image, chunk of output rows, group of channel blocks). Inside an
  // item the kernel walks tiles along W and, per tile, every block of the group, so
  // the input is read from memory about once, whole pixels at a time. Each item
  // restarts its rings of input rows, so chunks stay tall (16 rows measured best for
  // ConvNeXt's shapes, at least 8 when threads need items) and channel groups split
  // only when threads still lack items.
  const int lanes = lanes_of(w.isa());
  const int blocks = (is.c + lanes - 1) / lanes;
  const long long want = 4LL * threads;
  int chunk = os.h < 16 ? os.h : 16;
  while (threads > 1 && chunk > 8 && static_cast<long long>(os.n) * ((os.h + chunk - 1) / chunk) < want)
    chunk = (chunk + 1) / 2;
  const long long chunks = (os.h + chunk - 1) / chunk;
  int groups = 1;
  if (threads > 1 && os.n * chunks < want)
    groups = static_cast<int>(std::min<long long>(blocks, (want + os.n * chunks - 1) / (os.n * chunks)));
  const int group = (blocks + groups - 1) / groups;
  groups = (blocks + group - 1) / group;
  const long long items = static_cast<long long>(os.n) * chunks * groups;
  parallel_for(items, items > 1, [&](long long i_) {
    const long long i = static_cast<long long>(i_);
    const int n = static_cast<int>(i / (chunks * groups));
    const int y0 = static_cast<int>(i / groups % chunks) * chunk;
    const int y1 = y0 + chunk < os.h ? y0 + chunk : os.h;
    const int g0 = static_cast<int>(i % groups) * group;
    const int g1 = g0 + group < blocks ? g0 + group : blocks;
    block(job, n, g0, g1, y0, y1);
  });
}

void dwconv_rows(const ConstTensorView& in, const DwConvWeights& w, int n, int oy0, int oy1,
                 float* out) {
  const DwConvParams& p = packed_params(w);
  check_input(in, w.channels());
  if (!out) throw Error("dwconv: null tensor data");
  const Shape os = dwconv_output_shape(in.shape, p);
  if (n < 0 || n >= os.n || oy0 < 0 || oy0 > oy1 || oy1 > os.h)
    throw Error("dwconv: rows [" + std::to_string(oy0) + ", " + std::to_string(oy1) +
                ") of image " + std::to_string(n) + " are outside the " + std::to_string(os.n) +
                "x" + std::to_string(os.h) + " output");
  const std::ptrdiff_t row = static_cast<std::ptrdiff_t>(os.w) * os.c;
  if (overlaps(in.data, in.shape.count(), out, static_cast<std::size_t>(oy1 - oy0) * row))
    throw Error("dwconv: output overlaps the input");
  const DwConvBlockFn block = kernel_table(w.isa()).dwconv_block;
  if (!block) {
    for (int oy = oy0; oy < oy1; ++oy) dwconv_row_scalar(in, w, os.w, n, oy, out + (oy - oy0) * row);
    return;
  }
  DwConvJob job = make_job(in, w, os, out);
  job.out_image = 0;
  job.out_row0 = oy0;
  const int lanes = lanes_of(w.isa());
  block(job, n, 0, (os.c + lanes - 1) / lanes, oy0, oy1);
}

void dwconv_ref(const ConstTensorView& in, const float* w, const float* bias,
                const DwConvParams& p, const TensorView& out) {
  check_params(p);
  check_act(p.act);
  if (!w) throw Error("dwconv_ref: null weights");
  check_views(in, p, in.shape.c, out);
  const Shape& is = in.shape;
  for (int n = 0; n < out.shape.n; ++n)
    for (int oy = 0; oy < out.shape.h; ++oy)
      for (int ox = 0; ox < out.shape.w; ++ox)
        for (int ch = 0; ch < is.c; ++ch) {
          float acc = 0.0f;
          for (int ky = 0; ky < p.kh; ++ky) {
            const int iy = oy * p.stride_h - p.pad_h + ky;
            if (iy < 0 || iy >= is.h) continue;
            for (int kx = 0; kx < p.kw; ++kx) {
              const int ix = ox * p.stride_w - p.pad_w + kx;
              if (ix < 0 || ix >= is.w) continue;
              acc += in.pixel(n, iy, ix)[ch] * w[(static_cast<std::size_t>(ch) * p.kh + ky) * p.kw + kx];
            }
          }
          const float b = bias ? bias[ch] : 0.0f;
          out.pixel(n, oy, ox)[ch] = activate(acc + b, p.act);
        }
}

}  // namespace nn
