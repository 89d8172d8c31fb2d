// AVX-512 depthwise convolution: 16 channels per zmm.
//
// One call covers (image, output-row range, channel blocks). It goes tile by tile
// along W and, inside a tile, block by block: the tile's input for all channels is
// brought in from memory once, whole pixels at a time. For each block the input
// rows the tile needs are copied into a small ring of zero-padded row buffers
// ([position][16] floats; borders and the channel tail already zero), so the
// register kernels below never test a border or a channel mask. The ring of one
// block fits in L1, and walking down the rows brings in one new input row per
// output row (stride 1).
//
// Register kernel (stride-specialised "streaming" form): R output pixels along W in
// R accumulators; for each kernel row the KW weight vectors are loaded once and the
// (R-1)*S+KW input vectors of that row are streamed, each one feeding every
// accumulator whose window contains it. For 7x7 stride 1 with R = 12 that is 84
// FMAs per 18 input + 7 weight loads, so the FMA ports set the pace; R = 12 also
// divides ConvNeXt's widths (60 * 2^k), and measured a little faster than 14 or 16.
//
// Summation order of every output element: ky ascending, then kx ascending, one FMA
// per tap, starting from zero; bias added last. It does not depend on R, the tile or
// the row split, so any thread split gives bitwise identical results.
#include <immintrin.h>

#include <cstddef>

#include "nn/act.h"
#include "nn/dwconv_kernel.h"

// GCC 12's AVX-512 headers build masked intrinsics on a self-initialised
// "undefined" vector, which -Wmaybe-uninitialized reports at every inlined use.
#pragma GCC diagnostic ignored "-Wuninitialized"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"

namespace nn {
namespace {

constexpr int L = 16;
// Hard cap of the ring (kh * kw * L floats always fit) and the size tiles aim for.
constexpr int kRingFloats = kDwConvMaxTaps * L;
constexpr int kRingTargetFloats = kDwConvRingTargetBytes / 4;

struct BlockArgs {
  const float* const* rows;   // per valid kernel row: padded input row of the tile
  const float* const* wrows;  // per valid kernel row: its kw weight vectors
  int nrows;
  std::ptrdiff_t offset;      // float offset of the block's first input in each row
  int kw, sw;                 // used by the generic kernel only
  const float* bias;
  int act;
  float* out;                 // first output pixel of the block (channel c0)
  std::ptrdiff_t ostride;     // floats between output pixels (= c)
  __mmask16 mask;
  bool full;
};

inline __m512 activate(__m512 v, int act) {
  if (act == static_cast<int>(Act::Relu)) {
    // maxps returns its second operand for NaN, so NaN propagates as in torch.relu.
    return _mm512_max_ps(_mm512_setzero_ps(), v);
  }
  if (act == static_cast<int>(Act::HardSwish)) {
    __m512 t = _mm512_add_ps(v, _mm512_set1_ps(3.0f));
    t = _mm512_max_ps(_mm512_setzero_ps(), t);
    t = _mm512_min_ps(_mm512_set1_ps(6.0f), t);
    // x * relu6(x + 3) / 6 in PyTorch's order: multiply, then divide.
    return _mm512_div_ps(_mm512_mul_ps(v, t), _mm512_set1_ps(6.0f));
  }
  return v;
}

template <int R>
inline void finish(const BlockArgs& a, __m512 (&acc)[R]) {
  const __m512 b = _mm512_load_ps(a.bias);
#pragma GCC unroll 32
  for (int r = 0; r < R; ++r) {
    __m512 v = activate(_mm512_add_ps(acc[r], b), a.act);
    float* dst = a.out + r * a.ostride;
    if (a.full)
      _mm512_storeu_ps(dst, v);
    else
      _mm512_mask_storeu_ps(dst, a.mask, v);
  }
}

// Kernel width KW and stride S known at compile time.
template <int KW, int S, int R>
void stream_block(const BlockArgs& a) {
  __m512 acc[R];
#pragma GCC unroll 32
  for (int r = 0; r < R; ++r) acc[r] = _mm512_setzero_ps();
  constexpr int kInputs = (R - 1) * S + KW;
  for (int i = 0; i < a.nrows; ++i) {
    const float* x = a.rows[i] + a.offset;
    const float* wp = a.wrows[i];
    __m512 wv[KW];
#pragma GCC unroll 32
    for (int k = 0; k < KW; ++k) wv[k] = _mm512_load_ps(wp + k * L);
#pragma GCC unroll 64
    for (int j = 0; j < kInputs; ++j) {
      const __m512 v = _mm512_load_ps(x + j * L);
#pragma GCC unroll 32
      for (int r = 0; r < R; ++r) {
        const int kx = j - r * S;
        if (kx >= 0 && kx < KW) acc[r] = _mm512_fmadd_ps(v, wv[kx], acc[r]);
      }
    }
  }
  finish<R>(a, acc);
}

// Any kernel width and stride; same per-output order (ky, then kx).
template <int R>
void generic_block(const BlockArgs& a) {
  __m512 acc[R];
#pragma GCC unroll 32
  for (int r = 0; r < R; ++r) acc[r] = _mm512_setzero_ps();
  const std::ptrdiff_t step = static_cast<std::ptrdiff_t>(a.sw) * L;
  for (int i = 0; i < a.nrows; ++i) {
    const float* x = a.rows[i] + a.offset;
    const float* wp = a.wrows[i];
    for (int kx = 0; kx < a.kw; ++kx) {
      const __m512 wv = _mm512_load_ps(wp + kx * L);
      const float* xk = x + kx * L;
#pragma GCC unroll 32
      for (int r = 0; r < R; ++r) acc[r] = _mm512_fmadd_ps(_mm512_load_ps(xk + r * step), wv, acc[r]);
    }
  }
  finish<R>(a, acc);
}

// Selects the kernel instance for a block of `count` (< R) pixels at run time.
template <int KW, int S, int R>
struct Tail {
  static void run(int count, const BlockArgs& a) {
    if (count == R) {
      if constexpr (KW == 0)
        generic_block<R>(a);
      else
        stream_block<KW, S, R>(a);
    } else {
      Tail<KW, S, R - 1>::run(count, a);
    }
  }
};
template <int KW, int S>
struct Tail<KW, S, 0> {
  static void run(int, const BlockArgs&) {}
};

// Copies input row `src` (pixel 0, channel c0) positions [ix0, ix0 + count) into
// dst as [count][16], zero outside [0, w) and in the masked-off channel lanes.
void fill_row(float* dst, const float* src, int ix0, int count, int w, std::ptrdiff_t c,
              __mmask16 mask, bool full) {
  int p = 0;
  const __m512 zero = _mm512_setzero_ps();
  for (; p < count && ix0 + p < 0; ++p) _mm512_store_ps(dst + p * L, zero);
  int end = w - ix0;
  if (end > count) end = count;
  if (full) {
    for (; p < end; ++p) _mm512_store_ps(dst + p * L, _mm512_loadu_ps(src + (ix0 + p) * c));
  } else {
    for (; p < end; ++p)
      _mm512_store_ps(dst + p * L, _mm512_maskz_loadu_ps(mask, src + (ix0 + p) * c));
  }
  for (; p < count; ++p) _mm512_store_ps(dst + p * L, zero);
}

// KW == 0: generic kernel (run-time kernel width and stride). Tiles along W outside,
// channel blocks inside, so a tile's input (all channels) is brought in from memory
// once and each block's ring of padded rows is then built from cache.
template <int KW, int S, int R>
void run_rows(const DwConvJob& j, int n, int cb0, int cb1, int oy0, int oy1) {
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

  BlockArgs a;
  a.rows = rows;
  a.wrows = wrows;
  a.kw = kw;
  a.sw = sw;
  a.act = j.act;
  a.ostride = c;

  for (int ox0 = 0; ox0 < j.ow; ox0 += tw) {
    const int count = j.ow - ox0 < tw ? j.ow - ox0 : tw;
    const int width = (count - 1) * sw + kw;
    const int ix0 = ox0 * sw - j.pad_w;
    for (int cb = cb0; cb < cb1; ++cb) {
      const int c0 = cb * L;
      const int lanes = j.c - c0 < L ? j.c - c0 : L;
      const bool full = lanes == L;
      const __mmask16 mask = static_cast<__mmask16>((1u << lanes) - 1u);
      const float* taps = j.taps + static_cast<std::ptrdiff_t>(cb) * kh * kw * L;
      const float* img = j.in + static_cast<std::ptrdiff_t>(n) * j.h * j.w * c + c0;
      float* oimg = j.out + static_cast<std::ptrdiff_t>(n) * j.oh * j.ow * c + c0;
      a.bias = j.bias + c0;
      a.mask = mask;
      a.full = full;
      for (int s = 0; s < kh; ++s) tag[s] = -1;
      for (int oy = oy0; oy < oy1; ++oy) {
        int nrows = 0;
        for (int ky = 0; ky < kh; ++ky) {
          const int iy = oy * j.stride_h - j.pad_h + ky;
          if (iy < 0 || iy >= j.h) continue;
          const int slot = iy % kh;
          float* buf = ring + static_cast<std::ptrdiff_t>(slot) * slot_floats;
          if (tag[slot] != iy) {
            fill_row(buf, img + static_cast<std::ptrdiff_t>(iy) * j.w * c, ix0, width, j.w, c, mask,
                     full);
            tag[slot] = iy;
          }
          rows[nrows] = buf;
          wrows[nrows] = taps + static_cast<std::ptrdiff_t>(ky) * kw * L;
          ++nrows;
        }
        a.nrows = nrows;
        float* orow = oimg + (static_cast<std::ptrdiff_t>(oy) * j.ow + ox0) * c;
        // Full blocks of R; a remainder is merged with the last full block and split
        // in two halves, since a block much narrower than R has too few independent
        // accumulators to hide the FMA latency.
        const int rem = count % R;
        const int full_blocks = count / R - (rem && count >= R ? 1 : 0);
        int x = 0;
        for (int b = 0; b < full_blocks; ++b, x += R) {
          a.offset = static_cast<std::ptrdiff_t>(x) * sw * L;
          a.out = orow + x * c;
          if constexpr (KW == 0)
            generic_block<R>(a);
          else
            stream_block<KW, S, R>(a);
        }
        while (x < count) {
          const int left = count - x;
          const int part = left > R ? (left + 1) / 2 : left;
          a.offset = static_cast<std::ptrdiff_t>(x) * sw * L;
          a.out = orow + x * c;
          Tail<KW, S, R>::run(part, a);
          x += part;
        }
      }
    }
  }
}

}  // namespace

void dwconv_block_avx512(const DwConvJob& j, int n, int cb0, int cb1, int oy0,
                         int oy1) {
  if (j.stride_w == 1) {
    switch (j.kw) {
      case 7: return run_rows<7, 1, 12>(j, n, cb0, cb1, oy0, oy1);
      case 5: return run_rows<5, 1, 16>(j, n, cb0, cb1, oy0, oy1);
      case 3: return run_rows<3, 1, 16>(j, n, cb0, cb1, oy0, oy1);
      default: break;
    }
  } else if (j.stride_w == 2) {
    switch (j.kw) {
      case 5: return run_rows<5, 2, 12>(j, n, cb0, cb1, oy0, oy1);
      case 3: return run_rows<3, 2, 12>(j, n, cb0, cb1, oy0, oy1);
      default: break;
    }
  }
  run_rows<0, 0, 8>(j, n, cb0, cb1, oy0, oy1);
}

}  // namespace nn
