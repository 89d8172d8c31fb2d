// The depthwise convolution block kernel of nn/dwconv_kernel.h, written once over a
// per-ISA "vector ops" trait Ops (nn/arch/x86/vecops_avx2.h, vecops_avx512.h,
// nn/arch/arm/vecops_neon.h: L = Ops::kLanes channels per vector) and a tile-size struct
// Tiles, in an anonymous namespace: each ISA file (nn/arch/*/dwconv_*.cpp) instantiates
// it with its own flags in a few lines.
//
// One call covers (image, output-row range, channel blocks). It goes tile by tile
// along W and, inside a tile, block by block: the tile's input for all channels is
// brought in from memory once, whole pixels at a time. For each block the input
// rows the tile needs are copied into a small ring of zero-padded row buffers
// ([position][L] floats; borders and the channel tail already zero), so the
// register kernels below never test a border or a channel mask. The ring of one
// block fits in L1, and walking down the rows brings in one new input row per
// output row (stride 1).
//
// Register kernel (stride-specialised "streaming" form): R output pixels along W in
// R accumulators; for each kernel row the KW weight vectors are loaded once and the
// (R-1)*S+KW input vectors of that row are streamed, each one feeding every
// accumulator whose window contains it. R is the ISA's (Tiles): R accumulators + KW
// weights + 1 input must fit its register file. For AVX-512 7x7 stride 1 with R = 12
// that is 84 FMAs per 18 input + 7 weight loads, so the FMA ports set the pace; R = 12
// also divides ConvNeXt's widths (60 * 2^k), and measured a little faster than 14 or 16.
//
// Summation order of every output element: ky ascending, then kx ascending, one FMA
// per tap, starting from zero; bias added last. It does not depend on R, L, the tile
// or the row split, so any thread split and every ISA give bitwise identical results.
#pragma once

#include <cstddef>

#include "nn/act.h"
#include "nn/dwconv_kernel.h"

namespace nn {
namespace {

template <class Ops>
struct DwBlockArgs {
  const float* const* rows;   // per valid kernel row: padded input row of the tile
  const float* const* wrows;  // per valid kernel row: its kw weight vectors
  int nrows;
  std::ptrdiff_t offset;      // float offset of the block's first input in each row
  int kw, sw;                 // used by the generic kernel only
  const float* bias;
  int act;
  float* out;                 // first output pixel of the block (channel c0)
  std::ptrdiff_t ostride;     // floats between output pixels (= c)
  typename Ops::Mask mask;
  bool full;
};

template <class Ops>
inline typename Ops::V dw_activate(typename Ops::V v, int act) {
  if (act == static_cast<int>(Act::Relu)) {
    // NaN propagates as in torch.relu (see Ops::max).
    return Ops::max(Ops::zero(), v);
  }
  if (act == static_cast<int>(Act::HardSwish)) {
    typename Ops::V t = Ops::add(v, Ops::set1(3.0f));
    t = Ops::max(Ops::zero(), t);
    t = Ops::min(Ops::set1(6.0f), t);
    // x * relu6(x + 3) / 6 in PyTorch's order: multiply, then divide.
    return Ops::div(Ops::mul(v, t), Ops::set1(6.0f));
  }
  return v;
}

template <class Ops, int R>
inline void dw_finish(const DwBlockArgs<Ops>& a, typename Ops::V (&acc)[R]) {
  const typename Ops::V b = Ops::load(a.bias);
#pragma GCC unroll 32
  for (int r = 0; r < R; ++r) {
    const typename Ops::V v = dw_activate<Ops>(Ops::add(acc[r], b), a.act);
    float* dst = a.out + r * a.ostride;
    if (a.full)
      Ops::storeu(dst, v);
    else
      Ops::store_part(dst, a.mask, v);
  }
}

// Kernel width KW and stride S known at compile time.
template <class Ops, int KW, int S, int R>
void dw_stream_block(const DwBlockArgs<Ops>& a) {
  constexpr int L = Ops::kLanes;
  typename Ops::V acc[R];
#pragma GCC unroll 32
  for (int r = 0; r < R; ++r) acc[r] = Ops::zero();
  constexpr int kInputs = (R - 1) * S + KW;
  for (int i = 0; i < a.nrows; ++i) {
    const float* x = a.rows[i] + a.offset;
    const float* wp = a.wrows[i];
    typename Ops::V wv[KW];
#pragma GCC unroll 32
    for (int k = 0; k < KW; ++k) wv[k] = Ops::load(wp + k * L);
#pragma GCC unroll 64
    for (int j = 0; j < kInputs; ++j) {
      const typename Ops::V v = Ops::load(x + j * L);
#pragma GCC unroll 32
      for (int r = 0; r < R; ++r) {
        const int kx = j - r * S;
        if (kx >= 0 && kx < KW) acc[r] = Ops::fma(v, wv[kx], acc[r]);
      }
    }
  }
  dw_finish<Ops, R>(a, acc);
}

// Any kernel width and stride; same per-output order (ky, then kx).
template <class Ops, int R>
void dw_generic_block(const DwBlockArgs<Ops>& a) {
  constexpr int L = Ops::kLanes;
  typename Ops::V acc[R];
#pragma GCC unroll 32
  for (int r = 0; r < R; ++r) acc[r] = Ops::zero();
  const std::ptrdiff_t step = static_cast<std::ptrdiff_t>(a.sw) * L;
  for (int i = 0; i < a.nrows; ++i) {
    const float* x = a.rows[i] + a.offset;
    const float* wp = a.wrows[i];
    for (int kx = 0; kx < a.kw; ++kx) {
      const typename Ops::V wv = Ops::load(wp + kx * L);
      const float* xk = x + kx * L;
#pragma GCC unroll 32
      for (int r = 0; r < R; ++r) acc[r] = Ops::fma(Ops::load(xk + r * step), wv, acc[r]);
    }
  }
  dw_finish<Ops, R>(a, acc);
}

// R output pixels: KW == 0 selects the generic kernel.
template <class Ops, int KW, int S, int R>
inline void dw_block(const DwBlockArgs<Ops>& a) {
  if constexpr (KW == 0)
    dw_generic_block<Ops, R>(a);
  else
    dw_stream_block<Ops, KW, S, R>(a);
}

// Selects the kernel instance for a block of `count` (< R) pixels at run time.
template <class Ops, int KW, int S, int R>
struct DwTail {
  static void run(int count, const DwBlockArgs<Ops>& a) {
    if (count == R)
      dw_block<Ops, KW, S, R>(a);
    else
      DwTail<Ops, KW, S, R - 1>::run(count, a);
  }
};
template <class Ops, int KW, int S>
struct DwTail<Ops, KW, S, 0> {
  static void run(int, const DwBlockArgs<Ops>&) {}
};

// Copies input row `src` (pixel 0, channel c0) positions [ix0, ix0 + count) into
// dst as [count][L], zero outside [0, w) and in the masked-off channel lanes.
template <class Ops>
void dw_fill_row(float* dst, const float* src, int ix0, int count, int w, std::ptrdiff_t c,
                 typename Ops::Mask mask, bool full) {
  constexpr int L = Ops::kLanes;
  int p = 0;
  const typename Ops::V zero = Ops::zero();
  for (; p < count && ix0 + p < 0; ++p) Ops::store(dst + p * L, zero);
  int end = w - ix0;
  if (end > count) end = count;
  if (full) {
    for (; p < end; ++p) Ops::store(dst + p * L, Ops::loadu(src + (ix0 + p) * c));
  } else {
    for (; p < end; ++p) Ops::store(dst + p * L, Ops::load_part(src + (ix0 + p) * c, mask));
  }
  for (; p < count; ++p) Ops::store(dst + p * L, zero);
}

// Asks for positions [ix0, ix0 + count) (clipped to [0, w)) of input rows [iy0, iy1) of
// one channel block, `src` at its row 0 and pixel 0, to be brought into L2: one prefetch
// per pixel (an AVX-512 block is one 64-byte line; narrower ones share a line).
inline void dw_prefetch_rows(const float* src, int iy0, int iy1, int ix0, int count, int w,
                             std::ptrdiff_t c) {
  const int p0 = ix0 < 0 ? 0 : ix0;
  const int p1 = ix0 + count < w ? ix0 + count : w;
  for (int iy = iy0; iy < iy1; ++iy) {
    const float* row = src + static_cast<std::ptrdiff_t>(iy) * w * c;
    for (int p = p0; p < p1; ++p) __builtin_prefetch(row + p * c, 0, 2);
  }
}

// KW == 0: generic kernel (run-time kernel width and stride). Tiles along W outside,
// channel blocks inside, so a tile's input (all channels) is brought in from memory
// once and each block's ring of padded rows is then built from cache.
template <class Ops, int KW, int S, int R>
void dw_run_rows(const DwConvJob& j, int n, int cb0, int cb1, int oy0, int oy1) {
  constexpr int L = Ops::kLanes;
  // The size tiles aim for, and the ring: it holds that target, and the kh * kw * L
  // floats of the narrowest tile (one output pixel) for any kernel the packer accepts.
  constexpr int kRingTargetFloats = kDwConvRingTargetBytes / 4;
  constexpr int kRingFloats =
      kDwConvMaxTaps * L > kRingTargetFloats ? kDwConvMaxTaps * L : kRingTargetFloats;
  const int kh = j.kh, kw = j.kw, sw = KW == 0 ? j.stride_w : S;
  const std::ptrdiff_t c = j.c;

  // Widest tile (a multiple of R when possible) whose kh padded rows fit the target.
  int tw = ((kRingTargetFloats / (kh * L)) - kw) / sw + 1;
  if (tw >= R) tw -= tw % R;
  if (tw < 1) tw = 1;
  if (tw > j.ow) tw = j.ow;
  const int slot_floats = ((tw - 1) * sw + kw) * L;

  alignas(64) float ring[kRingFloats];
  int tag[kDwConvMaxKernel];
  const float* rows[kDwConvMaxKernel];
  const float* wrows[kDwConvMaxKernel];

  DwBlockArgs<Ops> a;
  a.rows = rows;
  a.wrows = wrows;
  a.kw = kw;
  a.sw = sw;
  a.act = j.act;
  a.ostride = c;

  // Input rows this call reads; while one (tile, block) is computed, those rows of the
  // next (tile, block) are prefetched into L2 a share per output row, so that its ring
  // fills find them there rather than wait on L3 or memory for each strided line (the
  // fills took as long as the FMAs without it: ConvNeXt's blocks read their input from
  // memory). Callers keep row ranges short (dwconv: chunks of <= 16 rows; ConvNeXt:
  // bands of 8), so the prefetched region stays far smaller than L2. Only for 7x7: with
  // MobileNetV3's 3x3 and 5x5 (fewer FMAs per input line) the prefetches cost more than
  // they saved (nn_bench BM_DwConv, Zen 5: 3-11 % slower).
  constexpr bool kPrefetchNext = KW == 7;
  const int iy_lo = oy0 * j.stride_h - j.pad_h < 0 ? 0 : oy0 * j.stride_h - j.pad_h;
  const int iy_hi = (oy1 - 1) * j.stride_h - j.pad_h + kh > j.h ? j.h : (oy1 - 1) * j.stride_h - j.pad_h + kh;
  const int in_rows = iy_hi - iy_lo, steps = oy1 - oy0;
  const float* img_n = j.in + static_cast<std::ptrdiff_t>(n) * j.h * j.w * c;

  // The tile starting at output column ox0: its output pixels, and the input positions
  // [ix0, ix0 + width) they read.
  struct TileSpan {
    int count, width, ix0;
  };
  const auto tile_at = [&](int ox0) {
    const int count = j.ow - ox0 < tw ? j.ow - ox0 : tw;
    return TileSpan{count, (count - 1) * sw + kw, ox0 * sw - j.pad_w};
  };

  for (int ox0 = 0; ox0 < j.ow; ox0 += tw) {
    const TileSpan tile = tile_at(ox0);
    const int count = tile.count, width = tile.width, ix0 = tile.ix0;
    for (int cb = cb0; cb < cb1; ++cb) {
      const int c0 = cb * L;
      const int lanes = j.c - c0 < L ? j.c - c0 : L;
      const bool full = lanes == L;
      const typename Ops::Mask mask = Ops::mask(lanes);
      const float* taps = j.taps + static_cast<std::ptrdiff_t>(cb) * kh * kw * L;
      const float* img = img_n + c0;
      float* oimg = j.out + static_cast<std::ptrdiff_t>(n) * j.out_image + c0;
      a.bias = j.bias + c0;
      a.mask = mask;
      a.full = full;
      for (int s = 0; s < kh; ++s) tag[s] = -1;
      // The (tile, block) after this one: the next block, or the next tile's first.
      int next_c0 = -1;
      TileSpan next = tile;
      if (cb + 1 < cb1) {
        next_c0 = (cb + 1) * L;
      } else if (ox0 + tw < j.ow) {
        next_c0 = cb0 * L;
        next = tile_at(ox0 + tw);
      }
      for (int oy = oy0; oy < oy1; ++oy) {
        if (kPrefetchNext && next_c0 >= 0) {
          const int k = oy - oy0;
          dw_prefetch_rows(img_n + next_c0, iy_lo + in_rows * k / steps, iy_lo + in_rows * (k + 1) / steps,
                           next.ix0, next.width, j.w, c);
        }
        int nrows = 0;
        for (int ky = 0; ky < kh; ++ky) {
          const int iy = oy * j.stride_h - j.pad_h + ky;
          if (iy < 0 || iy >= j.h) continue;
          const int slot = iy % kh;
          float* buf = ring + static_cast<std::ptrdiff_t>(slot) * slot_floats;
          if (tag[slot] != iy) {
            dw_fill_row<Ops>(buf, img + static_cast<std::ptrdiff_t>(iy) * j.w * c, ix0, width,
                             j.w, c, mask, full);
            tag[slot] = iy;
          }
          rows[nrows] = buf;
          wrows[nrows] = taps + static_cast<std::ptrdiff_t>(ky) * kw * L;
          ++nrows;
        }
        a.nrows = nrows;
        float* orow = oimg + (static_cast<std::ptrdiff_t>(oy - j.out_row0) * j.ow + ox0) * c;
        // Full blocks of R; a remainder is merged with the last full block and split
        // in two halves, since a block much narrower than R has too few independent
        // accumulators to hide the FMA latency.
        const int rem = count % R;
        const int full_blocks = count / R - (rem && count >= R ? 1 : 0);
        int x = 0;
        for (int b = 0; b < full_blocks; ++b, x += R) {
          a.offset = static_cast<std::ptrdiff_t>(x) * sw * L;
          a.out = orow + x * c;
          dw_block<Ops, KW, S, R>(a);
        }
        while (x < count) {
          const int left = count - x;
          const int part = left > R ? (left + 1) / 2 : left;
          a.offset = static_cast<std::ptrdiff_t>(x) * sw * L;
          a.out = orow + x * c;
          DwTail<Ops, KW, S, R>::run(part, a);
          x += part;
        }
      }
    }
  }
}

// The entry point of every ISA: the stride-specialised kernels for the shapes the
// models use, the generic one otherwise. Tiles gives each one's register tile R:
//   struct Tiles { static constexpr int k7s1, k5s1, k3s1, k5s2, k3s2, generic; };
template <class Ops, class Tiles>
void dwconv_block_with(const DwConvJob& j, int n, int cb0, int cb1, int oy0, int oy1) {
  if (j.stride_w == 1) {
    switch (j.kw) {
      case 7: return dw_run_rows<Ops, 7, 1, Tiles::k7s1>(j, n, cb0, cb1, oy0, oy1);
      case 5: return dw_run_rows<Ops, 5, 1, Tiles::k5s1>(j, n, cb0, cb1, oy0, oy1);
      case 3: return dw_run_rows<Ops, 3, 1, Tiles::k3s1>(j, n, cb0, cb1, oy0, oy1);
      default: break;
    }
  } else if (j.stride_w == 2) {
    switch (j.kw) {
      case 5: return dw_run_rows<Ops, 5, 2, Tiles::k5s2>(j, n, cb0, cb1, oy0, oy1);
      case 3: return dw_run_rows<Ops, 3, 2, Tiles::k3s2>(j, n, cb0, cb1, oy0, oy1);
      default: break;
    }
  }
  dw_run_rows<Ops, 0, 0, Tiles::generic>(j, n, cb0, cb1, oy0, oy1);
}

}  // namespace
}  // namespace nn
