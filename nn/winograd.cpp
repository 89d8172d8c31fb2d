// Winograd F(4x4, 3x3): weight transform and packing, tiling, threading, and the
// scalar transforms (nn/winograd_transform.h with V = float).
//
// Per block of T tiles (one thread):
//   input transform   36 x [T x C_in]   V, one row per tile, zero outside the image
//   36 GEMMs          M_xi = V_xi * U_xi  [T x C_out]
//   output transform  16 pixels per tile, epilogue, only the pixels inside the image
// A tile's arithmetic is the same in any block, so the split over threads (and T) never
// changes an output bit.
#include "nn/winograd.h"

#include <algorithm>
#include <cstring>
#include <string>

#include "nn/activation.h"
#include "nn/error.h"
#include "nn/exec.h"
#include "nn/threads.h"
#include "nn/kernel_table.h"
#include "nn/winograd_kernel.h"
#include "nn/winograd_transform.h"

namespace nn {

ExecOptions& mutable_exec();  // nn/exec.cpp

namespace {


// G of F(4x4, 3x3) (the filter transform), points 0, +-1, +-2, infinity.
constexpr double kG[6][3] = {{1.0 / 4, 0, 0},
                             {-1.0 / 6, -1.0 / 6, -1.0 / 6},
                             {-1.0 / 6, 1.0 / 6, -1.0 / 6},
                             {1.0 / 24, 1.0 / 12, 1.0 / 6},
                             {1.0 / 24, -1.0 / 12, 1.0 / 6},
                             {0, 0, 1}};

// Scratch of the blocks aims at about this many bytes per thread (V and M of T tiles):
// large enough for the GEMMs to reuse each transformed weight matrix over many rows,
// small enough to stay in the outer caches. bench/conv_bench.cpp on Emerald Rapids,
// 2 threads: 256 -> 256 channels at 192x336 88.4 / 82.1 / 84.8 ms with 3 / 6 / 12 MB,
// 512 -> 512 at 24x42 6.4 / 5.3 / 5.3 ms.
constexpr std::size_t kBlockTargetBytes = std::size_t{6} << 20;
constexpr int kMinBlockTiles = 16, kMaxBlockTiles = 128;

std::size_t round16(std::size_t floats) { return (floats + 15) / 16 * 16; }

using InputFn = void (*)(const WinogradInputTile&);
using OutputFn = void (*)(const WinogradOutputTile&);

InputFn input_fn(Isa isa) { return kernel_table(isa).winograd_input_tile; }
OutputFn output_fn(Isa isa) { return kernel_table(isa).winograd_output_tile; }

}  // namespace

void winograd_input_tile_scalar(const WinogradInputTile& t) { winograd_tile_with<float>(t); }
void winograd_output_tile_scalar(const WinogradOutputTile& t) { winograd_tile_with<float>(t); }

bool winograd_enabled() { return current_exec().winograd; }

void set_winograd(bool on) { mutable_exec().winograd = on; }

WinogradWeights WinogradWeights::pack(const float* w, int cin, int cout, Isa isa) {
  if (!w || cin < 1 || cout < 1)
    throw Error("winograd: cannot pack a [" + std::to_string(cout) + ", " + std::to_string(cin) + ", 3, 3] weight");
  WinogradWeights out;
  out.cin_ = cin;
  out.cout_ = cout;
  out.isa_ = isa;
  const std::size_t per = static_cast<std::size_t>(cin) * cout;
  std::vector<float> u(36 * per);  // u[xi][o][c]
  for (int o = 0; o < cout; ++o)
    for (int c = 0; c < cin; ++c) {
      const float* g = w + (static_cast<std::size_t>(o) * cin + c) * 9;
      double gg[6][3];  // G g
      for (int i = 0; i < 6; ++i)
        for (int b = 0; b < 3; ++b)
          gg[i][b] = kG[i][0] * g[b] + kG[i][1] * g[3 + b] + kG[i][2] * g[6 + b];
      for (int i = 0; i < 6; ++i)
        for (int j = 0; j < 6; ++j) {
          const double v = gg[i][0] * kG[j][0] + gg[i][1] * kG[j][1] + gg[i][2] * kG[j][2];
          u[(i * 6 + j) * per + static_cast<std::size_t>(o) * cin + c] = static_cast<float>(v);
        }
    }
  out.u_.reserve(36);
  for (int xi = 0; xi < 36; ++xi) out.u_.push_back(GemmWeights::pack(u.data() + xi * per, cout, cin, isa));
  return out;
}

std::size_t WinogradWeights::bytes() const {
  std::size_t b = 0;
  for (const auto& g : u_) b += g.bytes();
  return b;
}

int winograd_block_tiles(int cin, int cout) {
  const std::size_t per_tile = 36 * sizeof(float) * (static_cast<std::size_t>(cin) + cout);
  const std::size_t t = kBlockTargetBytes / per_tile;
  return static_cast<int>(std::clamp<std::size_t>(t / 8 * 8, kMinBlockTiles, kMaxBlockTiles));
}

std::size_t winograd_scratch_floats(int cin, int cout) {
  const std::size_t t = static_cast<std::size_t>(winograd_block_tiles(cin, cout));
  return round16(36 * t * cin) + round16(36 * t * cout) + round16(cin);
}

void winograd_conv2d(const ConstTensorView& in, const WinogradWeights& w, const float* bias,
                     const TensorView& out, float* scratch, Act act, const float* residual,
                     bool act_after_residual) {
  if (w.empty()) throw Error("winograd: weights were not packed");
  const int cin = w.cin(), cout = w.cout();
  if (in.shape.c != cin || out.shape.c != cout || out.shape.n != in.shape.n || out.shape.h != in.shape.h ||
      out.shape.w != in.shape.w)
    throw Error("winograd: tensor shapes " + shape_str(in.shape) + " -> " + shape_str(out.shape) +
                " do not match a 3x3 stride-1 pad-1 convolution " + std::to_string(cin) + " -> " +
                std::to_string(cout));
  if (!scratch) throw Error("winograd: no scratch");
  const int h = in.shape.h, wd = in.shape.w;
  const int th = (h + 3) / 4, tw = (wd + 3) / 4;
  const long tiles = static_cast<long>(in.shape.n) * th * tw;
  if (tiles == 0) return;
  const int tmax = winograd_block_tiles(cin, cout);
  const std::size_t per_thread = winograd_scratch_floats(cin, cout);
  // Blocks of at most tmax tiles, a multiple of the team so that no thread idles.
  const int team = std::max(1, num_threads());
  const long blocks = team * ((tiles + static_cast<long>(team) * tmax - 1) / (static_cast<long>(team) * tmax));
  const long per_block = (tiles + blocks - 1) / blocks;
  const InputFn input = input_fn(w.isa());
  const OutputFn output = output_fn(w.isa());
  const bool fused_act = act == Act::None || act == Act::Relu;
  const std::ptrdiff_t vs = static_cast<std::ptrdiff_t>(tmax) * cin, ms = static_cast<std::ptrdiff_t>(tmax) * cout;
  parallel_for(blocks, true, [&](long long b_) {
    const long b = static_cast<long>(b_);
    const long t0 = b * per_block, t1 = std::min(tiles, t0 + per_block);
    if (t0 >= t1) return;
    float* v = scratch + per_thread * thread_index();
    float* m = v + round16(36 * static_cast<std::size_t>(tmax) * cin);
    float* zero = m + round16(36 * static_cast<std::size_t>(tmax) * cout);
    std::memset(zero, 0, sizeof(float) * cin);
    auto tile_origin = [&](long t, int* n, int* y, int* x) {
      *n = static_cast<int>(t / (static_cast<long>(th) * tw));
      const long r = t % (static_cast<long>(th) * tw);
      *y = static_cast<int>(r / tw) * 4;
      *x = static_cast<int>(r % tw) * 4;
    };
    for (long t = t0; t < t1; ++t) {
      int n, y0, x0;
      tile_origin(t, &n, &y0, &x0);
      WinogradInputTile job;
      for (int r = 0; r < 6; ++r) {
        const int y = y0 - 1 + r;
        for (int c = 0; c < 6; ++c) {
          const int x = x0 - 1 + c;
          job.src[r * 6 + c] = y >= 0 && y < h && x >= 0 && x < wd ? in.pixel(n, y, x) : zero;
        }
      }
      job.c = cin;
      job.v = v + (t - t0) * cin;
      job.xi_stride = vs;
      input(job);
    }
    const int rows = static_cast<int>(t1 - t0);
    for (int xi = 0; xi < 36; ++xi) gemm(rows, v + xi * vs, cin, w.product(xi), m + xi * ms, cout);
    for (long t = t0; t < t1; ++t) {
      int n, y0, x0;
      tile_origin(t, &n, &y0, &x0);
      WinogradOutputTile job;
      job.m = m + (t - t0) * cout;
      job.xi_stride = ms;
      job.c = cout;
      job.bias = bias;
      job.relu_before = act == Act::Relu && !act_after_residual;
      job.relu_after = act == Act::Relu && act_after_residual;
      for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) {
          const int y = y0 + r, x = x0 + c;
          const bool inside = y < h && x < wd;
          float* px = inside ? out.pixel(n, y, x) : nullptr;
          job.dst[r * 4 + c] = px;
          job.res[r * 4 + c] = inside && residual && fused_act ? residual + (px - out.data) : nullptr;
        }
      output(job);
      if (fused_act) continue;
      // Other activations: the same epilogue order on the tile's pixels while in cache.
      for (int p = 0; p < 16; ++p) {
        float* px = job.dst[p];
        if (!px) continue;
        const float* res = residual ? residual + (px - out.data) : nullptr;
        if (!act_after_residual) apply_act(act, px, cout, w.isa());
        if (res)
          for (int c = 0; c < cout; ++c) px[c] = px[c] + res[c];
        if (act_after_residual) apply_act(act, px, cout, w.isa());
      }
    }
  });
}

}  // namespace nn
