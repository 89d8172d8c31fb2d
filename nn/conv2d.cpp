#include "nn/conv2d.h"

#include <algorithm>
#include <array>
#include <cstring>
#include <utility>
#include <vector>

#include "nn/activation.h"
#include "nn/error.h"
#include "nn/threads.h"

namespace nn {

namespace {

void check_params(const Conv2dParams& p) {
  if (p.cin <= 0 || p.cout <= 0 || p.kh <= 0 || p.kw <= 0 || p.stride_h <= 0 ||
      p.stride_w <= 0 || p.pad_h < 0 || p.pad_w < 0 || p.groups <= 0 || p.cin % p.groups ||
      p.cout % p.groups)
    throw Error("conv2d: invalid parameters");
}

}  // namespace

bool Conv2dWeights::is_pointwise() const {
  return p_.kh == 1 && p_.kw == 1 && p_.stride_h == 1 && p_.stride_w == 1 && p_.pad_h == 0 &&
         p_.pad_w == 0;
}

bool conv2d_winograd_applies(const Conv2dParams& p) {
  return p.kh == 3 && p.kw == 3 && p.stride_h == 1 && p.stride_w == 1 && p.pad_h == 1 && p.pad_w == 1 &&
         p.groups == 1 && p.cin >= kWinogradMinChannels && p.cout >= kWinogradMinChannels;
}

Conv2dWeights Conv2dWeights::pack(const float* w, const float* bias, const Conv2dParams& p,
                                  Isa isa) {
  check_params(p);
  if (p.groups != 1) throw Error("conv2d: grouped convolution is not supported by the GEMM path");
  if (!w) throw Error("conv2d: weight pointer is null");
  Conv2dWeights out;
  out.p_ = p;
  if (bias) {
    out.bias_.resize(p.cout);
    std::memcpy(out.bias_.data(), bias, sizeof(float) * p.cout);
  }
  if (conv2d_winograd_applies(p) && winograd_enabled()) {
    out.winograd_ = WinogradWeights::pack(w, p.cin, p.cout, isa);
    return out;
  }
  // im2col rows are ordered (ky, kx, c) because NHWC keeps a pixel's channels
  // contiguous; PyTorch stores (c, ky, kx), so reorder before packing.
  const int k = p.kh * p.kw * p.cin;
  std::vector<float> reordered(static_cast<std::size_t>(p.cout) * k);
  for (int o = 0; o < p.cout; ++o)
    for (int c = 0; c < p.cin; ++c)
      for (int ky = 0; ky < p.kh; ++ky)
        for (int kx = 0; kx < p.kw; ++kx)
          reordered[static_cast<std::size_t>(o) * k + (ky * p.kw + kx) * p.cin + c] =
              w[((static_cast<std::size_t>(o) * p.cin + c) * p.kh + ky) * p.kw + kx];
  out.gemm_ = GemmWeights::pack(reordered.data(), p.cout, k, isa);
  return out;
}

Shape conv2d_output_shape(const Shape& in, const Conv2dParams& p) {
  Shape s;
  s.n = in.n;
  s.h = (in.h + 2 * p.pad_h - p.kh) / p.stride_h + 1;
  s.w = (in.w + 2 * p.pad_w - p.kw) / p.stride_w + 1;
  s.c = p.cout;
  if (in.h + 2 * p.pad_h < p.kh || in.w + 2 * p.pad_w < p.kw) s.h = s.w = 0;
  return s;
}

int conv2d_block_rows(int out_w) { return out_w >= kConvBlockPixels ? 1 : (kConvBlockPixels + out_w - 1) / out_w; }

std::size_t conv2d_scratch_floats(const Conv2dWeights& w, int out_w) {
  const Conv2dParams& p = w.params();
  if (w.is_winograd()) return winograd_scratch_floats(p.cin, p.cout);
  if (w.is_pointwise()) return 0;
  return static_cast<std::size_t>(conv2d_block_rows(out_w)) * out_w * p.kh * p.kw * p.cin;
}

namespace {

// Copies and clears of up to kSmallCopy floats go through fixed-size memcpy/memset the
// compiler expands inline: the stems' patch rows are 9 (3x3, 3 channels) or 21 (7x7)
// floats, and a library call per row cost more than the copy (MobileNetV3's stem
// im2col took 6 of its 9 ms at 720p).
constexpr int kSmallCopy = 32;

template <int N>
struct Small {
  static void copy(float* d, const float* s) { std::memcpy(d, s, sizeof(float) * N); }
  static void zero(float* d) { std::memset(d, 0, sizeof(float) * N); }
};
template <int... N>
constexpr std::array<void (*)(float*, const float*), sizeof...(N)> copy_table(std::integer_sequence<int, N...>) {
  return {&Small<N>::copy...};
}
template <int... N>
constexpr std::array<void (*)(float*), sizeof...(N)> zero_table(std::integer_sequence<int, N...>) {
  return {&Small<N>::zero...};
}
constexpr auto kCopy = copy_table(std::make_integer_sequence<int, kSmallCopy + 1>{});
constexpr auto kZero = zero_table(std::make_integer_sequence<int, kSmallCopy + 1>{});

inline void copy_floats(float* d, const float* s, int n) {
  if (n <= kSmallCopy) kCopy[n](d, s);
  else std::memcpy(d, s, sizeof(float) * n);
}
inline void zero_floats(float* d, int n) {
  if (n <= kSmallCopy) kZero[n](d);
  else std::memset(d, 0, sizeof(float) * n);
}

// im2col of output row oy into `col`: row ox holds the (ky, kx, c) patch, zeros outside.
void im2col_row(const ConstTensorView& in, const Conv2dParams& p, int n, int oy, int ow, float* col) {
  const int cin = p.cin, k = p.kh * p.kw * cin;
  for (int ox = 0; ox < ow; ++ox, col += k) {
    const int ix0 = ox * p.stride_w - p.pad_w;
    for (int ky = 0; ky < p.kh; ++ky) {
      const int iy = oy * p.stride_h - p.pad_h + ky;
      float* row = col + static_cast<std::size_t>(ky) * p.kw * cin;
      if (iy < 0 || iy >= in.shape.h) {
        zero_floats(row, p.kw * cin);
        continue;
      }
      // Columns [kx_lo, kx_hi) of this kernel row fall inside the image.
      const int kx_lo = std::min(p.kw, std::max(0, -ix0));
      const int kx_hi = std::max(kx_lo, std::min(p.kw, in.shape.w - ix0));
      zero_floats(row, kx_lo * cin);
      if (kx_hi > kx_lo)
        copy_floats(row + static_cast<std::size_t>(kx_lo) * cin, in.pixel(n, iy, ix0 + kx_lo), (kx_hi - kx_lo) * cin);
      zero_floats(row + static_cast<std::size_t>(kx_hi) * cin, (p.kw - kx_hi) * cin);
    }
  }
}

}  // namespace

void conv2d_rows(const ConstTensorView& in, const Conv2dWeights& w, const TensorView& out, int n,
                 int y0, int y1, float* scratch, Act act, const float* residual,
                 bool act_after_residual) {
  if (w.is_winograd()) throw Error("conv2d: conv2d_rows() takes direct weights; Winograd layers run through conv2d()");
  const Conv2dParams& p = w.params();
  const int ow = out.shape.w, cin = p.cin;
  const int k = p.kh * p.kw * cin;
  const int block = conv2d_block_rows(ow);
  GemmEpilogue ep;
  ep.bias = w.bias();
  ep.act = act;
  ep.act_after_residual = act_after_residual;
  ep.ldr = out.shape.c;
  // Output rows of an NHWC image are contiguous, so a block of rows is one product
  // with M = rows * ow; the K summation order does not depend on M.
  for (int oy = y0; oy < y1; oy += block) {
    const int rows = std::min(block, y1 - oy);
    float* dst = out.pixel(n, oy, 0);
    ep.residual = residual ? residual + (dst - out.data) : nullptr;
    if (w.is_pointwise()) {
      gemm(rows * ow, in.pixel(n, oy, 0), cin, w.gemm(), dst, out.shape.c, ep);
      continue;
    }
    for (int r = 0; r < rows; ++r) im2col_row(in, p, n, oy + r, ow, scratch + static_cast<std::size_t>(r) * ow * k);
    gemm(rows * ow, scratch, k, w.gemm(), dst, out.shape.c, ep);
  }
}

void conv2d(const ConstTensorView& in, const Conv2dWeights& w, const TensorView& out,
            float* scratch, Act act, const float* residual, bool act_after_residual) {
  if (in.shape.c != w.params().cin || out.shape != conv2d_output_shape(in.shape, w.params()))
    throw Error("conv2d: tensor shapes do not match the convolution");
  if (w.is_winograd()) {
    winograd_conv2d(in, w.winograd(), w.bias(), out, scratch, act, residual, act_after_residual);
    return;
  }
  const std::size_t per_thread = conv2d_scratch_floats(w, out.shape.w);
  // Blocks of at most conv2d_block_rows() rows, as many per image as a multiple of the
  // team so no thread idles on small maps (the result does not depend on the split).
  const int team = std::max(1, num_threads()), h = out.shape.h;
  const int max_block = conv2d_block_rows(out.shape.w);
  const int wanted = team * ((h + team * max_block - 1) / (team * max_block));
  const int block = std::max(1, (h + wanted - 1) / wanted);
  const int blocks_per_image = (h + block - 1) / block;
  const int blocks = out.shape.n * blocks_per_image;
  parallel_for(blocks, true, [&](long long b_) {
    const int b = static_cast<int>(b_);
    float* mine = scratch ? scratch + per_thread * thread_index() : nullptr;
    const int n = b / blocks_per_image, y0 = (b % blocks_per_image) * block;
    const int y1 = std::min(h, y0 + block);
    conv2d_rows(in, w, out, n, y0, y1, mine, act, residual, act_after_residual);
  });
}

void conv2d_ref(const ConstTensorView& in, const float* w, const float* bias,
                const Conv2dParams& p, const TensorView& out, Act act) {
  check_params(p);
  const int cin_g = p.cin / p.groups, cout_g = p.cout / p.groups;
  for (int n = 0; n < out.shape.n; ++n)
    for (int oy = 0; oy < out.shape.h; ++oy)
      for (int ox = 0; ox < out.shape.w; ++ox)
        for (int o = 0; o < p.cout; ++o) {
          const int g = o / cout_g;
          double acc = bias ? bias[o] : 0.0;
          for (int c = 0; c < cin_g; ++c)
            for (int ky = 0; ky < p.kh; ++ky) {
              const int iy = oy * p.stride_h - p.pad_h + ky;
              if (iy < 0 || iy >= in.shape.h) continue;
              for (int kx = 0; kx < p.kw; ++kx) {
                const int ix = ox * p.stride_w - p.pad_w + kx;
                if (ix < 0 || ix >= in.shape.w) continue;
                acc += static_cast<double>(in.pixel(n, iy, ix)[g * cin_g + c]) *
                       w[((static_cast<std::size_t>(o) * cin_g + c) * p.kh + ky) * p.kw + kx];
              }
            }
          out.pixel(n, oy, ox)[o] = act_ref(act, static_cast<float>(acc));
        }
}

}  // namespace nn
