#include "nn/threads.h"
#include "nn/layout.h"

#include <cstddef>
#include <string>

#include "nn/error.h"

namespace nn {
namespace {

// The strided side of a transpose touches one cache line per row of the tile, and
// when the plane size is a multiple of 4 KiB (320x480, 640x960, ...) all those lines
// fall into the same L1 set: that side of the tile stays at 8 rows, fewer than the
// ways of an L1 set, while the contiguous side takes 64 floats (whole lines).
constexpr long long kWide = 64;
constexpr long long kNarrow = 8;

std::size_t check(const char* who, const float* src, int n, int c, int h, int w,
                  const float* dst) {
  if (n < 0 || c < 0 || h < 0 || w < 0)
    throw Error(std::string(who) + ": negative size [" + std::to_string(n) + "," +
                std::to_string(c) + "," + std::to_string(h) + "," + std::to_string(w) + "]");
  const std::size_t count = static_cast<std::size_t>(n) * c * h * w;
  if (count == 0) return 0;
  if (!src || !dst) throw Error(std::string(who) + ": null source or destination");
  if (src < dst + count && dst < src + count)
    throw Error(std::string(who) + ": destination overlaps the source");
  return count;
}

// [planes][rows][cols] -> [planes][cols][rows] where rows is the large stride of the
// source (NCHW -> NHWC: rows = c, cols = h*w). Per item: 64 columns, all rows in
// strips of 8 (the 64 x rows output block stays in L1 while its strips arrive).
void transpose_rows_strided(const float* src, float* dst, long long planes, long long rows,
                            long long cols) {
  const long long col_tiles = (cols + kWide - 1) / kWide;
  const long long items = planes * col_tiles;
  parallel_for(items, planes * rows * cols > 65536, [&](long long it_) {
    const long long it = static_cast<long long>(it_);
    const float* s = src + it / col_tiles * rows * cols;
    float* d = dst + it / col_tiles * rows * cols;
    const long long j0 = it % col_tiles * kWide;
    const long long j1 = j0 + kWide < cols ? j0 + kWide : cols;
    for (long long i0 = 0; i0 < rows; i0 += kNarrow) {
      const long long i1 = i0 + kNarrow < rows ? i0 + kNarrow : rows;
      for (long long j = j0; j < j1; ++j)
        for (long long i = i0; i < i1; ++i) d[j * rows + i] = s[i * cols + j];
    }
  });
}

// The same where cols is the large stride of the destination (NHWC -> NCHW: rows =
// h*w, cols = c). Per item: 64 rows, all columns in strips of 8.
void transpose_cols_strided(const float* src, float* dst, long long planes, long long rows,
                            long long cols) {
  const long long row_tiles = (rows + kWide - 1) / kWide;
  const long long items = planes * row_tiles;
  parallel_for(items, planes * rows * cols > 65536, [&](long long it_) {
    const long long it = static_cast<long long>(it_);
    const float* s = src + it / row_tiles * rows * cols;
    float* d = dst + it / row_tiles * rows * cols;
    const long long i0 = it % row_tiles * kWide;
    const long long i1 = i0 + kWide < rows ? i0 + kWide : rows;
    for (long long j0 = 0; j0 < cols; j0 += kNarrow) {
      const long long j1 = j0 + kNarrow < cols ? j0 + kNarrow : cols;
      for (long long j = j0; j < j1; ++j)
        for (long long i = i0; i < i1; ++i) d[j * rows + i] = s[i * cols + j];
    }
  });
}

}  // namespace

void nchw_to_nhwc(const float* src, int n, int c, int h, int w, float* dst) {
  if (check("nchw_to_nhwc", src, n, c, h, w, dst) == 0) return;
  // Per image: [c][h*w] -> [h*w][c].
  transpose_rows_strided(src, dst, n, c, static_cast<long long>(h) * w);
}

void nhwc_to_nchw(const float* src, int n, int c, int h, int w, float* dst) {
  if (check("nhwc_to_nchw", src, n, c, h, w, dst) == 0) return;
  // Per image: [h*w][c] -> [c][h*w].
  transpose_cols_strided(src, dst, n, static_cast<long long>(h) * w, c);
}

}  // namespace nn
