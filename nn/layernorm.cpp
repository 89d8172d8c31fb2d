#include "nn/threads.h"
#include "nn/layernorm.h"

#include <cmath>
#include <string>

#include "nn/error.h"
#include "nn/isa.h"
#include "nn/kernel_table.h"
#include "nn/layernorm_kernel.h"

namespace nn {
namespace {

void check_args(const char* who, std::size_t rows, int c, const float* x, std::ptrdiff_t ldx,
                const float* y, std::ptrdiff_t ldy) {
  if (c < 1) throw Error(std::string(who) + ": channel count must be positive, got " + std::to_string(c));
  if (rows == 0) return;
  if (!x || !y) throw Error(std::string(who) + ": null input or output");
  if ((rows > 1 && (ldx < c || ldy < c)) || ldx < 0 || ldy < 0)
    throw Error(std::string(who) + ": row strides " + std::to_string(ldx) + ", " +
                std::to_string(ldy) + " are smaller than the " + std::to_string(c) + " channels");
}

// Scalar path, the vector kernels' algorithm with eight lanes: partial sums over
// i mod 8 folded by halves, so rounding grows like theirs rather than like one long
// chain; provisional mean m, then sums of d = x - m and d^2, and the correction
// delta = sum(d) / c for the rounding of m (see nn/layernorm_rows.h).
float fold8(const float* s) {
  return ((s[0] + s[4]) + (s[2] + s[6])) + ((s[1] + s[5]) + (s[3] + s[7]));
}

void layernorm_row_scalar(int c, const float* x, float* y, const float* gamma, const float* beta,
                          float eps) {
  const float cf = static_cast<float>(c);
  float s[8] = {};
  for (int i = 0; i < c; ++i) s[i % 8] += x[i];
  const float m = fold8(s) / cf;

  float q[8] = {}, e[8] = {};
  for (int i = 0; i < c; ++i) {
    const float d = x[i] - m;
    q[i % 8] += d * d;
    e[i % 8] += d;
  }
  const float delta = fold8(e) / cf;
  float var = (fold8(q) - delta * delta * cf) / cf;
  if (!(var > 0.0f)) var = 0.0f;
  const float rstd = 1.0f / std::sqrt(var + eps);
  for (int i = 0; i < c; ++i) {
    const float t = ((x[i] - m) - delta) * rstd;
    y[i] = (gamma ? t * gamma[i] : t) + (beta ? beta[i] : 0.0f);
  }
}

}  // namespace

void layernorm(std::size_t rows, int c, const float* x, std::ptrdiff_t ldx, float* y,
               std::ptrdiff_t ldy, const float* gamma, const float* beta, float eps) {
  layernorm(rows, c, x, ldx, y, ldy, gamma, beta, eps, active_isa());
}

void layernorm(std::size_t rows, int c, const float* x, std::ptrdiff_t ldx, float* y,
               std::ptrdiff_t ldy, const float* gamma, const float* beta, float eps, Isa isa) {
  check_args("layernorm", rows, c, x, ldx, y, ldy);
  kernel_table(isa).layernorm_rows(rows, c, x, ldx, y, ldy, gamma, beta, eps);
}

void layernorm_rows_scalar(std::size_t rows, int c, const float* x, std::ptrdiff_t ldx, float* y,
                           std::ptrdiff_t ldy, const float* gamma, const float* beta, float eps) {
  for (std::size_t r = 0; r < rows; ++r)
    layernorm_row_scalar(c, x + static_cast<std::ptrdiff_t>(r) * ldx,
                         y + static_cast<std::ptrdiff_t>(r) * ldy, gamma, beta, eps);
}

void layernorm_parallel(std::size_t rows, int c, const float* x, std::ptrdiff_t ldx, float* y,
                        std::ptrdiff_t ldy, const float* gamma, const float* beta, float eps) {
  check_args("layernorm", rows, c, x, ldx, y, ldy);
  const Isa isa = active_isa();
#ifdef ROADNN_THREADS
  const int threads = team_size();
  // Rows in multiples of 4 per chunk keep the kernels' groups full; a row's result
  // does not depend on its group anyway.
  const std::size_t min_rows = 256;
  if (threads > 1 && rows >= 2 * min_rows) {
    const std::size_t chunks = static_cast<std::size_t>(threads) * 4;
    std::size_t chunk = ((rows + chunks - 1) / chunks + 3) / 4 * 4;
    if (chunk < min_rows) chunk = min_rows;
    const long long n = static_cast<long long>((rows + chunk - 1) / chunk);
    parallel_for(n, true, [&](long long i_) {
      const long long i = static_cast<long long>(i_);
      const std::size_t r0 = static_cast<std::size_t>(i) * chunk;
      const std::size_t r1 = r0 + chunk < rows ? r0 + chunk : rows;
      layernorm(r1 - r0, c, x + static_cast<std::ptrdiff_t>(r0) * ldx, ldx,
                y + static_cast<std::ptrdiff_t>(r0) * ldy, ldy, gamma, beta, eps, isa);
    });
    return;
  }
#endif
  layernorm(rows, c, x, ldx, y, ldy, gamma, beta, eps, isa);
}

void layernorm_ref(std::size_t rows, int c, const float* x, std::ptrdiff_t ldx, float* y,
                   std::ptrdiff_t ldy, const float* gamma, const float* beta, float eps) {
  check_args("layernorm_ref", rows, c, x, ldx, y, ldy);
  // Double precision throughout: the accuracy yardstick for the float kernels.
  for (std::size_t r = 0; r < rows; ++r) {
    const float* xr = x + static_cast<std::ptrdiff_t>(r) * ldx;
    float* yr = y + static_cast<std::ptrdiff_t>(r) * ldy;
    double sum = 0.0;
    for (int i = 0; i < c; ++i) sum += xr[i];
    const double mean = sum / c;
    double sq = 0.0;
    for (int i = 0; i < c; ++i) sq += (xr[i] - mean) * (xr[i] - mean);
    const double rstd = 1.0 / std::sqrt(sq / c + static_cast<double>(eps));
    for (int i = 0; i < c; ++i) {
      const double t = (xr[i] - mean) * rstd;
      yr[i] = static_cast<float>((gamma ? t * gamma[i] : t) + (beta ? beta[i] : 0.0));
    }
  }
}

}  // namespace nn
