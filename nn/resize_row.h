// The bilinear resize row of nn/resize_kernel.h, written once over a per-ISA "vector
// ops" trait Ops (nn/arch/x86/vecops_avx2.h, nn/arch/arm/vecops_neon.h; L = Ops::kLanes
// channels per vector), in an anonymous namespace: each ISA file instantiates it with its
// own flags. Per element the same three fused multiply-adds as the scalar path
// (nn/resize.cpp), in the same order, so every ISA gives the scalar path's bits:
//   y = fma(fma(a, w0, b * w1), h0, fma(c, w0, d * w1) * h1)
#pragma once

#include "nn/resize_kernel.h"

namespace nn {
namespace {

template <class Ops>
void resize_bilinear_row_with(const float* row0, const float* row1, float h0, float h1,
                              const long long* x0, const long long* x1, const float* w0,
                              const float* w1, int count, int c, float* out) {
  using V = typename Ops::V;
  constexpr int L = Ops::kLanes;
  const V vh0 = Ops::set1(h0), vh1 = Ops::set1(h1);
  const int tail = c % L;
  const typename Ops::Mask mask = Ops::mask(tail);
  for (int i = 0; i < count; ++i, out += c) {
    const float *a = row0 + x0[i], *b = row0 + x1[i], *p = row1 + x0[i], *q = row1 + x1[i];
    const V vw0 = Ops::set1(w0[i]), vw1 = Ops::set1(w1[i]);
    int ch = 0;
    for (; ch + L <= c; ch += L) {
      const V t0 = Ops::fma(Ops::loadu(a + ch), vw0, Ops::mul(Ops::loadu(b + ch), vw1));
      const V t1 = Ops::fma(Ops::loadu(p + ch), vw0, Ops::mul(Ops::loadu(q + ch), vw1));
      Ops::storeu(out + ch, Ops::fma(t0, vh0, Ops::mul(t1, vh1)));
    }
    if (tail) {
      const V t0 = Ops::fma(Ops::load_part(a + ch, mask), vw0,
                            Ops::mul(Ops::load_part(b + ch, mask), vw1));
      const V t1 = Ops::fma(Ops::load_part(p + ch, mask), vw0,
                            Ops::mul(Ops::load_part(q + ch, mask), vw1));
      Ops::store_part(out + ch, mask, Ops::fma(t0, vh0, Ops::mul(t1, vh1)));
    }
  }
}

}  // namespace
}  // namespace nn
