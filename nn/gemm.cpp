// Packing, cache blocking and threading around the micro-kernels of nn/gemm_kernels.h,
// the portable scalar kernel, and the reference.
//
// Blocking (per gemm() call, rows [m0, m1), panels [p0, p1)):
//   for each block of MC rows
//     for each chunk of panels whose MC x NC partial sums fit the scratch tile
//       for each K block (KC steps; one block when K is small)
//         for each W panel (NR columns) of the chunk
//           for each MR rows of the block: micro-kernel
// The MR x KC slice of A and the KC x NR slice of the panel stay in L1/L2 while the
// inner loops reuse them, and each tile prefetches a slice of the W block the loops
// reach next (W of the large layers streams from L3 once per row block). Intermediate K
// blocks go to the scratch tile (on the stack), never to C, so a residual that aliases C
// is intact when the last block's epilogue reads it.
#include "nn/threads.h"
#include "nn/gemm.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "nn/activation.h"
#include "nn/error.h"
#include "nn/gemm_kernels.h"
#include "nn/kernel_table.h"

namespace nn {
namespace {

// Blocking; see the top of this file. Measured on the ConvNeXt-Tiny shapes with
// bench/gemm_bench.cpp (Zen 5): KC 384..512 beats 256 and 768+; MC 32..256 and the scratch
// size make no measurable difference, so MC matches the model's 64-row fused tiles.
constexpr int kMc = 64;             // rows per block (rounded down to a multiple of MR)
constexpr int kKcMax = 512;         // K steps per block
constexpr int kPartialFloats = 12288;  // scratch tile for intermediate K blocks (48 KiB)

float epilogue_scalar(float acc, int n, const float* residual_elem, const GemmEpilogue& ep) {
  float v = acc;
  if (ep.bias) v = v + ep.bias[n];
  if (!ep.act_after_residual) v = act_ref(ep.act, v);
  if (ep.scale) v = v * ep.scale[n];
  if (residual_elem) v = v + *residual_elem;
  if (ep.act_after_residual) v = act_ref(ep.act, v);
  return v;
}

// The portable kernel (no FMA: a multiply and an add per step, in k order).
template <int R>
void scalar_tile(const GemmTile& t) {
  constexpr int NR = 16;
  float acc[R][NR];
  for (int r = 0; r < R; ++r)
    for (int j = 0; j < NR; ++j) acc[r][j] = t.acc ? t.acc[r * t.ld_acc + j] : 0.0f;
  for (int k = 0; k < t.kc; ++k) {
    const float* wk = t.w + static_cast<std::ptrdiff_t>(k) * NR;
    for (int r = 0; r < R; ++r) {
      const float a = t.a[r * t.lda + k];
      for (int j = 0; j < NR; ++j) acc[r][j] = acc[r][j] + a * wk[j];
    }
  }
  if (!t.ep) {
    for (int r = 0; r < R; ++r)
      for (int j = 0; j < NR; ++j) t.c[r * t.ldc + j] = acc[r][j];
    return;
  }
  const GemmTileEpilogue& te = *t.ep;
  GemmEpilogue ep;
  ep.bias = te.bias;
  ep.scale = te.scale;
  ep.act = static_cast<Act>(te.act);
  ep.act_after_residual = te.act_after_residual;
  for (int r = 0; r < R; ++r)
    for (int j = 0; j < t.nr; ++j) {
      const float* res = te.residual ? te.residual + r * te.ldr + j : nullptr;
      t.c[r * t.ldc + j] = epilogue_scalar(acc[r][j], j, res, ep);
    }
}

template <int R>
void scalar_dispatch(const GemmTile& t) {
  if (t.mr == R) return scalar_tile<R>(t);
  if constexpr (R > 1) scalar_dispatch<R - 1>(t);
}

}  // namespace

#define NN_GEMM_DEFINE_Scalar(fn, mr, nr) \
  static_assert((nr) == 16, #fn ": the scalar kernel has NR = 16"); \
  void fn(const GemmTile& tile) { scalar_dispatch<mr>(tile); }
#define NN_GEMM_DEFINE_Avx2(fn, mr, nr)
#define NN_GEMM_DEFINE_Avx512(fn, mr, nr)
#define NN_GEMM_DEFINE_Neon(fn, mr, nr)
#define NN_GEMM_DEFINE(fn, isa, mr, nr) NN_GEMM_DEFINE_##isa(fn, mr, nr)
NN_GEMM_UKERNELS(NN_GEMM_DEFINE)
#undef NN_GEMM_DEFINE

namespace {

#define NN_GEMM_TABLE_ENTRY(fn, isa, mr, nr) {#fn, Isa::isa, mr, nr, &fn},
const GemmUkernelInfo kUkernels[] = {NN_GEMM_UKERNELS(NN_GEMM_TABLE_ENTRY)};
#undef NN_GEMM_TABLE_ENTRY
constexpr int kUkernelCount = static_cast<int>(sizeof(kUkernels) / sizeof(kUkernels[0]));

#define NN_GEMM_CHECK_NR(fn, isa, mr, nr)                                      \
  static_assert(kMc * (nr) <= kPartialFloats, #fn ": NR too wide for the K-block scratch"); \
  static_assert((mr) <= kMc, #fn ": MR above the row block");
NN_GEMM_UKERNELS(NN_GEMM_CHECK_NR)
#undef NN_GEMM_CHECK_NR

}  // namespace

int gemm_ukernel_count() { return kUkernelCount; }

const GemmUkernelInfo& gemm_ukernel(int ukernel) {
  if (ukernel < 0 || ukernel >= kUkernelCount)
    throw Error("gemm: no micro-kernel #" + std::to_string(ukernel));
  return kUkernels[ukernel];
}

int gemm_default_ukernel(Isa isa) {
  for (int i = 0; i < kUkernelCount; ++i)
    if (kUkernels[i].isa == isa) return i;
  throw Error(std::string("gemm: no micro-kernel for ISA ") + isa_name(isa));
}

int gemm_ukernel_for(Isa isa, int n) {
  const int def = gemm_default_ukernel(isa);
  if (n <= 0) return def;
  const int lanes = kernel_table(isa).lanes;
  auto cost = [n, lanes](int u) {
    const int nr = kUkernels[u].nr;
    return static_cast<double>((n + nr - 1) / nr * nr) * (nr == lanes ? 1.2 : 1.0);
  };
  int best = def;
  for (int i = 0; i < kUkernelCount; ++i)
    if (kUkernels[i].isa == isa && cost(i) < cost(best)) best = i;
  return cost(def) > 1.1 * cost(best) ? best : def;
}

const char* gemm_kernel_name(Isa isa, int n) { return kUkernels[gemm_ukernel_for(isa, n)].name; }

GemmWeights GemmWeights::pack(const float* w, int n, int k, Isa isa) {
  return pack_for_ukernel(w, n, k, gemm_ukernel_for(isa, n));
}

GemmWeights GemmWeights::pack_for_ukernel(const float* w, int n, int k, int ukernel) {
  const GemmUkernelInfo& info = gemm_ukernel(ukernel);
  if (n <= 0 || k <= 0)
    throw Error("gemm: cannot pack a weight matrix of shape [" + std::to_string(n) + " x " +
                std::to_string(k) + "]");
  if (!w) throw Error("gemm: weight pointer is null");
  if (!isa_supported(info.isa))
    throw Error(std::string("gemm: ") + info.name + " needs " + isa_name(info.isa) +
                ", which this CPU does not support");
  GemmWeights out;
  const int nr = info.nr;
  const std::size_t panels = static_cast<std::size_t>((n + nr - 1) / nr);
  out.data_.resize(panels * static_cast<std::size_t>(k) * nr);  // zero-filled: padded columns
  float* dst = out.data_.data();
  for (std::size_t p = 0; p < panels; ++p)
    for (int kk = 0; kk < k; ++kk)
      for (int j = 0; j < nr; ++j) {
        const std::size_t col = p * nr + j;
        if (col < static_cast<std::size_t>(n))
          dst[(p * k + kk) * nr + j] = w[col * static_cast<std::size_t>(k) + kk];
      }
  out.n_ = n;
  out.k_ = k;
  out.isa_ = info.isa;
  out.ukernel_ = ukernel;
  return out;
}

namespace {

void check_call(int m, std::ptrdiff_t lda, const GemmWeights& w, const float* a, const float* c,
                std::ptrdiff_t ldc, const GemmEpilogue& ep) {
  if (w.ukernel() < 0) throw Error("gemm: weights were not packed");
  if (m < 0) throw Error("gemm: negative row count " + std::to_string(m));
  if (m > 0 && (!a || !c)) throw Error("gemm: null A or C");
  if (lda < w.k())
    throw Error("gemm: lda " + std::to_string(lda) + " < K " + std::to_string(w.k()));
  if (ldc < w.n())
    throw Error("gemm: ldc " + std::to_string(ldc) + " < N " + std::to_string(w.n()));
  if (static_cast<int>(ep.act) < static_cast<int>(Act::None) ||
      static_cast<int>(ep.act) > static_cast<int>(Act::Sigmoid))
    throw Error("gemm: unknown activation " + std::to_string(static_cast<int>(ep.act)));
  if (ep.residual && ep.ldr < w.n())
    throw Error("gemm: ldr " + std::to_string(ep.ldr) + " < N " + std::to_string(w.n()));
}

GemmPacked packed(const GemmWeights& w) {
  const GemmUkernelInfo& info = gemm_ukernel(w.ukernel());
  return {w.panels(), w.n(), w.k(), info.mr, info.nr, info.fn};
}

}  // namespace

void gemm_blocked(int m0, int m1, int p0, int p1, const float* a, std::ptrdiff_t lda,
                  const GemmPacked& w, float* c, std::ptrdiff_t ldc, const GemmEpilogue& ep) {
  const int mr = w.mr, nr = w.nr, n = w.n, k = w.k;
  // A block of at most a few hundred rows (a thread's share of a small-M GEMM split by
  // columns) is one row block when its partial sums fit the scratch tile: W then streams
  // from L3 once instead of once per kMc rows. Blocking never changes the K order.
  const int rows_up = (m1 - m0 + mr - 1) / mr * mr;
  const int mc = rows_up <= 4 * kMc && rows_up * nr <= kPartialFloats
                     ? rows_up
                     : std::max(mr, kMc / mr * mr);
  const int kblocks = (k + kKcMax - 1) / kKcMax;
  const int kc = (k + kblocks - 1) / kblocks;  // equal blocks, the last one shorter
  // Panels per chunk: all of them without K blocking, else as many as the scratch holds
  // (at least one: kMc * NR <= kPartialFloats for every kernel, see kUkernels).
  const int chunk = kblocks == 1 ? p1 - p0 : kPartialFloats / (mc * nr);
  const std::ptrdiff_t ldp = static_cast<std::ptrdiff_t>(chunk) * nr;
  alignas(64) float partial[kPartialFloats];
  const float* panels = w.panels;
  const std::size_t panel_stride = static_cast<std::size_t>(k) * nr;
  auto w_block = [&](int j, int kb) {
    return panels + j * panel_stride + static_cast<std::size_t>(kb) * kc * nr;
  };

  GemmTile t{};
  t.lda = lda;
  t.ld_acc = ldp;
  GemmTileEpilogue te{};
  te.ldr = ep.ldr;
  te.act = static_cast<int>(ep.act);
  te.act_after_residual = ep.act_after_residual;

  for (int ic = m0; ic < m1; ic += mc) {
    const int ie = std::min(m1, ic + mc);
    const int row_tiles = (ie - ic + mr - 1) / mr;
    for (int jc = p0; jc < p1; jc += chunk) {
      const int je = std::min(p1, jc + chunk);
      for (int kb = 0; kb < kblocks; ++kb) {
        const int k0 = kb * kc;
        t.kc = std::min(kc, k - k0);
        const bool first = kb == 0, last = kb == kblocks - 1;
        for (int j = jc; j < je; ++j) {
          // The W block the loops reach next, prefetched in slices over this panel's tiles.
          int next_j = -1, next_kb = 0;
          if (j + 1 < je) {
            next_j = j + 1;
            next_kb = kb;
          } else if (kb + 1 < kblocks) {
            next_j = jc;
            next_kb = kb + 1;
          } else if (je < p1 || ie < m1) {
            next_j = je < p1 ? je : p0;
          }
          const float* next = next_j < 0 ? nullptr : w_block(next_j, next_kb);
          const int next_lines = next_j < 0 ? 0 : std::min(kc, k - next_kb * kc) * nr / 16;
          const int lines_per_tile = (next_lines + row_tiles - 1) / row_tiles;
          t.w = w_block(j, kb);
          t.nr = std::min(nr, n - j * nr);
          for (int i = ic, q = 0; i < ie; i += mr, ++q) {
            t.a = a + i * lda + k0;
            t.mr = std::min(mr, ie - i);
            const std::ptrdiff_t poff = static_cast<std::ptrdiff_t>(i - ic) * ldp + (j - jc) * nr;
            t.acc = first ? nullptr : partial + poff;
            t.pf_lines = std::max(0, std::min(lines_per_tile, next_lines - q * lines_per_tile));
            const std::ptrdiff_t pf_offset = static_cast<std::ptrdiff_t>(q) * lines_per_tile * 16;
            t.pf = t.pf_lines > 0 ? next + pf_offset : nullptr;
            if (last) {
              t.c = c + i * ldc + j * nr;
              t.ldc = ldc;
              te.bias = ep.bias ? ep.bias + j * nr : nullptr;
              te.scale = ep.scale ? ep.scale + j * nr : nullptr;
              te.residual = ep.residual ? ep.residual + i * ep.ldr + j * nr : nullptr;
              t.ep = &te;
            } else {
              t.c = partial + poff;
              t.ldc = ldp;
              t.ep = nullptr;
            }
            w.fn(t);
          }
        }
      }
    }
  }
}

void gemm_split(int m, const float* a, std::ptrdiff_t lda, const GemmPacked& w, float* c,
                std::ptrdiff_t ldc, const GemmEpilogue& ep) {
  const int panels = (w.n + w.nr - 1) / w.nr;
#ifdef ROADNN_THREADS
  const int threads = team_size();
  if (threads > 1) {
    const int mr = w.mr;
    const int row_tiles = (m + mr - 1) / mr;
    // Rows alone when every thread gets a few row blocks; otherwise a grid that also
    // splits the panels. Either way each element is computed once, by the same kernel.
    // Columns when each thread's row share is small (ConvNeXt stages 3-4 at 224x224) and
    // there are enough panels to balance: each thread then streams only its part of W.
    int tn = 1;
    if (m < 64 * threads || (m < 128 * threads && panels >= 4 * threads))
      tn = std::min(threads, panels);
    const int tm = std::max(1, std::min(threads / tn, row_tiles));
    parallel_team(tm * tn, [&](int id, int) {
      const int im = id / tn, in = id % tn;
      const int rows_per = (row_tiles + tm - 1) / tm * mr;
      const int r0 = std::min(m, im * rows_per), r1 = std::min(m, r0 + rows_per);
      const int p0 = in * panels / tn, p1 = (in + 1) * panels / tn;
      if (r0 < r1 && p0 < p1) gemm_blocked(r0, r1, p0, p1, a, lda, w, c, ldc, ep);
    });
    return;
  }
#endif
  gemm_blocked(0, m, 0, panels, a, lda, w, c, ldc, ep);
}

void gemm(int m, const float* a, std::ptrdiff_t lda, const GemmWeights& w, float* c,
          std::ptrdiff_t ldc, const GemmEpilogue& ep) {
  check_call(m, lda, w, a, c, ldc, ep);
  if (m == 0) return;
  const GemmPacked p = packed(w);
  gemm_blocked(0, m, 0, (p.n + p.nr - 1) / p.nr, a, lda, p, c, ldc, ep);
}

void gemm_parallel(int m, const float* a, std::ptrdiff_t lda, const GemmWeights& w, float* c,
                   std::ptrdiff_t ldc, const GemmEpilogue& ep) {
  check_call(m, lda, w, a, c, ldc, ep);
  if (m == 0) return;
  gemm_split(m, a, lda, packed(w), c, ldc, ep);
}

void gemm_ref(int m, int n, int k, const float* a, std::ptrdiff_t lda, const float* w, float* c,
              std::ptrdiff_t ldc, const GemmEpilogue& ep) {
  // Double accumulation, rounded once to float; then the float epilogue.
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < n; ++j) {
      double s = 0.0;
      for (int kk = 0; kk < k; ++kk)
        s += static_cast<double>(a[i * lda + kk]) *
             static_cast<double>(w[j * static_cast<std::ptrdiff_t>(k) + kk]);
      const float* res = ep.residual ? ep.residual + i * ep.ldr + j : nullptr;
      c[i * ldc + j] = epilogue_scalar(static_cast<float>(s), j, res, ep);
    }
}

}  // namespace nn
