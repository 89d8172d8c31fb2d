// Interface between nn/resize.cpp and its ISA kernels (nn/kernel_table.h). Declarations only: the ISA
// file includes it, so it must not define inline functions or templates.
#pragma once

namespace nn {

// One output row segment of bilinear resizing: for pixel i, the four inputs are
// row0/row1 + x0[i] / x1[i] (float offsets), with column weights w0[i], w1[i] and
// row weights h0, h1; c channels per pixel; out advances c per pixel.
//   y = fma(fma(a, w0, b * w1), h0, fma(c, w0, d * w1) * h1)
using ResizeBilinearRowFn = void (*)(const float* row0, const float* row1, float h0, float h1,
                                     const long long* x0, const long long* x1, const float* w0,
                                     const float* w1, int count, int c, float* out);
void resize_bilinear_row_scalar(const float* row0, const float* row1, float h0, float h1,
                                const long long* x0, const long long* x1, const float* w0,
                                const float* w1, int count, int c, float* out);
void resize_bilinear_row_neon(const float* row0, const float* row1, float h0, float h1,
                              const long long* x0, const long long* x1, const float* w0,
                              const float* w1, int count, int c, float* out);
void resize_bilinear_row_avx2(const float* row0, const float* row1, float h0, float h1,
                              const long long* x0, const long long* x1, const float* w0,
                              const float* w1, int count, int c, float* out);

}  // namespace nn
