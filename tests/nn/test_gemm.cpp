// GEMM: every micro-kernel of the list in nn/gemm_kernels.h, and the bf16 GEMM of
// nn/gemm_bf16.h, against gemm_ref on awkward shapes and every epilogue; bitwise
// determinism across row splits, thread counts and K blocking; argument errors.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "nn/activation.h"
#include "nn/error.h"
#include "nn/gemm.h"
#include "nn/gemm_bf16.h"
#include "nn/gemm_kernels.h"
#include "nn/exec.h"
#include "nn/threads.h"
#include "tests/nn/isa_param.h"
#include "tests/nn/random_data.h"
#include "tests/reference/torch_ref.h"

namespace {

using nntest::random_vector;
using nn::Act;
using nn::GemmEpilogue;
using nn::GemmWeights;

constexpr Act kActs[] = {Act::None, Act::Relu, Act::Gelu, Act::HardSwish, Act::HardSigmoid,
                         Act::Sigmoid};

// A packed GEMM under test: one float micro-kernel of the list, or the bf16 GEMM. The
// bf16 GEMM's tests draw A and W already representable in bfloat16, so its rounding is
// exact and gemm_ref is its exact reference too.
struct Variant {
  int ukernel = -1;  // -1: the bf16 GEMM
  int mr = 0;
  std::string name;
  bool bf16() const { return ukernel < 0; }
};

std::vector<Variant> supported_variants() {
  std::vector<Variant> out;
  for (int i = 0; i < nn::gemm_ukernel_count(); ++i)
    if (nn::isa_supported(nn::gemm_ukernel(i).isa))
      out.push_back({i, nn::gemm_ukernel(i).mr, nn::gemm_ukernel(i).name});
  if (nn::bf16_gemm_available()) out.push_back({-1, 8, nn::gemm_bf16_kernel_name()});
  return out;
}

void PrintTo(const Variant& v, std::ostream* os) { *os << v.name; }

std::string variant_test_name(const testing::TestParamInfo<Variant>& info) { return info.param.name; }

// Random values for A or W; for the bf16 GEMM rounded to bfloat16 (exactly representable).
std::vector<float> operand(const Variant& v, std::size_t n, unsigned seed) {
  std::vector<float> x = random_vector(n, seed);
  if (v.bf16())
    for (float& e : x) e = nn::bf16_to_f32(nn::f32_to_bf16(e));
  return x;
}

class PackedProduct {
 public:
  PackedProduct(const Variant& v, const float* w, int n, int k) : k_(k) {
    if (v.bf16())
      bf16_ = nn::GemmWeightsBf16::pack(w, n, k);
    else
      f32_ = GemmWeights::pack_for_ukernel(w, n, k, v.ukernel);
  }
  void gemm(int m, const float* a, std::ptrdiff_t lda, float* c, std::ptrdiff_t ldc,
            const GemmEpilogue& ep, bool parallel = false) const {
    if (bf16_.empty()) {
      if (parallel) return nn::gemm_parallel(m, a, lda, f32_, c, ldc, ep);
      return nn::gemm(m, a, lda, f32_, c, ldc, ep);
    }
    const std::ptrdiff_t ldb = k_ + (k_ & 1) + 2;  // even, and wider than the row
    std::vector<nn::bf16> ab(static_cast<std::size_t>(std::max(m, 1)) * ldb, 0xFFFF);
    nn::convert_to_bf16(m, k_, a, lda, ab.data(), ldb);
    if (parallel) return nn::gemm_bf16_parallel(m, ab.data(), ldb, bf16_, c, ldc, ep);
    nn::gemm_bf16(m, ab.data(), ldb, bf16_, c, ldc, ep);
  }

 private:
  int k_;
  GemmWeights f32_;
  nn::GemmWeightsBf16 bf16_;
};

enum class Residual { None, Separate, AliasC };

struct EpilogueCase {
  bool bias = false;
  Act act = Act::None;
  bool scale = false;
  Residual residual = Residual::None;
  bool act_after_residual = false;
};

std::string describe(int m, int n, int k, const EpilogueCase& e) {
  static const char* kRes[] = {"none", "separate", "alias-C"};
  return "m " + std::to_string(m) + " n " + std::to_string(n) + " k " + std::to_string(k) +
         " bias " + std::to_string(e.bias) + " act " + std::to_string(static_cast<int>(e.act)) +
         " scale " + std::to_string(e.scale) + " residual " +
         kRes[static_cast<int>(e.residual)] + " after " + std::to_string(e.act_after_residual);
}

// One product through the packed kernel and through gemm_ref, compared element-wise:
// |y - ref| <= 1.5 * 1e-5 * sum_k |a||w| * max(1, |scale|) + 1e-6 * |ref| + 3e-6
// (1.5: the largest activation slope; 3e-6 covers the vector GELU/sigmoid error).
void check_product(const Variant& v, int m, int n, int k, const EpilogueCase& e, unsigned seed) {
  SCOPED_TRACE(describe(m, n, k, e));
  const std::ptrdiff_t lda = k + 5, ldc = n + 3;
  const std::ptrdiff_t ldr = e.residual == Residual::AliasC ? ldc : n + 7;
  const std::vector<float> a = operand(v, static_cast<std::size_t>(m) * lda, seed);
  const std::vector<float> w = operand(v, static_cast<std::size_t>(n) * k, seed + 1);
  const std::vector<float> bias = random_vector(n, seed + 2);
  const std::vector<float> scale = random_vector(n, seed + 3, -2.0f, 2.0f);
  const std::vector<float> res =
      random_vector(static_cast<std::size_t>(m) * ldr, seed + 4, -3.0f, 3.0f);
  // Sentinel between rows: the kernels must not write outside [m x n].
  std::vector<float> c(static_cast<std::size_t>(m) * ldc, 12345.0f);
  std::vector<float> c_ref(c.size(), 12345.0f);
  if (e.residual == Residual::AliasC) {
    c = res;
    c_ref = res;
  }
  auto make_ep = [&](float* cbuf) {
    GemmEpilogue ep;
    ep.bias = e.bias ? bias.data() : nullptr;
    ep.act = e.act;
    ep.scale = e.scale ? scale.data() : nullptr;
    ep.act_after_residual = e.act_after_residual;
    if (e.residual == Residual::Separate) ep.residual = res.data();
    if (e.residual == Residual::AliasC) ep.residual = cbuf;
    ep.ldr = ldr;
    return ep;
  };
  const PackedProduct packed(v, w.data(), n, k);
  packed.gemm(m, a.data(), lda, c.data(), ldc, make_ep(c.data()));
  nn::gemm_ref(m, n, k, a.data(), lda, w.data(), c_ref.data(), ldc, make_ep(c_ref.data()));
  int failures = 0;
  for (int i = 0; i < m && failures < 5; ++i) {
    for (int j = 0; j < ldc; ++j) {
      const std::size_t idx = static_cast<std::size_t>(i) * ldc + j;
      if (j >= n) {
        const float expect = e.residual == Residual::AliasC ? res[idx] : 12345.0f;
        if (c[idx] != expect && ++failures <= 5)
          ADD_FAILURE() << "wrote outside C at row " << i << " col " << j;
        continue;
      }
      double mag = 0.0;
      for (int kk = 0; kk < k; ++kk)
        mag += std::fabs(static_cast<double>(a[i * lda + kk]) *
                         w[static_cast<std::size_t>(j) * k + kk]);
      const double sc = e.scale ? std::max(1.0, std::fabs(static_cast<double>(scale[j]))) : 1.0;
      const double tol = 1.5e-5 * mag * sc + 1e-6 * std::fabs(c_ref[idx]) + 3e-6;
      if (!(std::fabs(static_cast<double>(c[idx]) - c_ref[idx]) <= tol) && ++failures <= 5)
        ADD_FAILURE() << "row " << i << " col " << j << ": " << c[idx] << " vs ref " << c_ref[idx]
                      << " (tol " << tol << ")";
    }
  }
}

class GemmUkernelTest : public testing::TestWithParam<Variant> {};

// Every awkward size against the reference; the epilogue rotates through all variants.
TEST_P(GemmUkernelTest, MatchesReferenceOnAwkwardShapes) {
  const int mr = GetParam().mr;
  std::vector<int> ms = {1, 2, mr - 1, mr, mr + 1, 37, 200};
  ms.erase(std::remove_if(ms.begin(), ms.end(), [](int v) { return v < 1; }), ms.end());
  std::sort(ms.begin(), ms.end());
  ms.erase(std::unique(ms.begin(), ms.end()), ms.end());
  const int ns[] = {1, 3, 15, 16, 17, 31, 33, 63, 65, 96, 100};
  const int ks[] = {1, 3, 17, 48, 96, 257, 600};
  unsigned seed = 1;
  for (int m : ms)
    for (int n : ns)
      for (int k : ks) {
        EpilogueCase e;
        e.bias = seed % 2 == 0;
        e.act = kActs[seed % 6];
        e.scale = seed % 3 == 0;
        e.residual = static_cast<Residual>(seed % 5 % 3);
        e.act_after_residual = seed % 7 == 0;
        check_product(GetParam(), m, n, k, e, seed);
        ++seed;
        if (HasFailure()) return;
      }
}

// Every epilogue combination on shapes with row and column tails and K blocking.
TEST_P(GemmUkernelTest, EveryEpilogueCombination) {
  const int shapes[][3] = {{GetParam().mr + 3, 37, 20}, {29, 100, 600}};
  unsigned seed = 1000;
  for (const auto& s : shapes)
    for (bool bias : {false, true})
      for (Act act : kActs)
        for (bool scale : {false, true})
          for (Residual r : {Residual::None, Residual::Separate, Residual::AliasC})
            for (bool after : {false, true}) {
              if (r == Residual::None && after) continue;  // same as before the residual
              EpilogueCase e{bias, act, scale, r, after};
              check_product(GetParam(), s[0], s[1], s[2], e, ++seed);
              if (HasFailure()) return;
            }
}

// K far beyond one K block: partial sums cross several blocks through the scratch tile.
TEST_P(GemmUkernelTest, LongK) {
  EpilogueCase e;
  e.bias = true;
  e.act = Act::Gelu;
  e.scale = true;
  e.residual = Residual::AliasC;
  check_product(GetParam(), 19, 70, 3100, e, 77);
}

// Every SIMD kernel (AVX2, AVX-512, NEON) computes each element as one float fused
// multiply-add per k in increasing k from zero, then the epilogue in float: bit for bit
// the std::fma chain below, so the ISAs give the same bits as each other. The shapes
// have every row tail up to 15 rows, column tails, K % 4 steps and K blocks. (The scalar
// kernel multiplies and adds: not this chain.) Only exact epilogue steps here: bias,
// ReLU, scale, residual.
TEST(GemmUkernelFma, SimdKernelsAreOneFmaPerKInIncreasingOrder) {
  std::vector<std::array<int, 3>> shapes = {{29, 100, 600}, {5, 19, 3100}};
  for (int m = 1; m <= 15; ++m) shapes.push_back({m, 37, 7});
  int checked = 0;
  for (int u = 0; u < nn::gemm_ukernel_count(); ++u) {
    const nn::GemmUkernelInfo& info = nn::gemm_ukernel(u);
    if (info.isa == nn::Isa::Scalar || !nn::isa_supported(info.isa)) continue;
    SCOPED_TRACE(info.name);
    ++checked;
    unsigned seed = 300;
    for (const auto& s : shapes) {
      const int m = s[0], n = s[1], k = s[2];
      SCOPED_TRACE("m " + std::to_string(m) + " n " + std::to_string(n) + " k " + std::to_string(k));
      const std::ptrdiff_t lda = k + 3, ldc = n + 1;
      const std::vector<float> a = random_vector(static_cast<std::size_t>(m) * lda, ++seed);
      const std::vector<float> w = random_vector(static_cast<std::size_t>(n) * k, ++seed);
      const std::vector<float> bias = random_vector(n, ++seed);
      const std::vector<float> scale = random_vector(n, ++seed, -2.0f, 2.0f);
      const std::vector<float> res = random_vector(static_cast<std::size_t>(m) * ldc, ++seed);
      const GemmWeights packed = GemmWeights::pack_for_ukernel(w.data(), n, k, u);
      for (Act act : {Act::None, Act::Relu})
        for (bool after : {false, true}) {
          GemmEpilogue ep;
          ep.bias = bias.data();
          ep.act = act;
          ep.scale = scale.data();
          ep.residual = res.data();
          ep.ldr = ldc;
          ep.act_after_residual = after;
          std::vector<float> c(static_cast<std::size_t>(m) * ldc, -7.0f);
          nn::gemm(m, a.data(), lda, packed, c.data(), ldc, ep);
          int failures = 0;
          for (int i = 0; i < m; ++i)
            for (int j = 0; j < n; ++j) {
              float v = 0.0f;
              for (int kk = 0; kk < k; ++kk)
                v = std::fma(a[static_cast<std::size_t>(i) * lda + kk],
                             w[static_cast<std::size_t>(j) * k + kk], v);
              v = v + bias[j];
              if (!after) v = nn::act_ref(act, v);
              v = v * scale[j];
              v = v + res[static_cast<std::size_t>(i) * ldc + j];
              if (after) v = nn::act_ref(act, v);
              const float got = c[static_cast<std::size_t>(i) * ldc + j];
              if (std::memcmp(&got, &v, sizeof v) != 0 && ++failures <= 5)
                ADD_FAILURE() << "act " << static_cast<int>(act) << " after " << after << " row " << i
                              << " col " << j << ": " << got << " vs fma chain " << v;
            }
          ASSERT_EQ(failures, 0);
        }
    }
  }
  // A machine with a SIMD ISA has a kernel for it in the list (x86-64: AVX2; aarch64: NEON).
  EXPECT_EQ(checked > 0, nn::detect_isa() != nn::Isa::Scalar);
}

struct DeterminismCase {
  int m, n, k;
};

// Runs C = epilogue(A W^T) with the residual aliasing C, starting from the same C.
class AliasedProduct {
 public:
  AliasedProduct(const Variant& v, int m, int n, int k)
      : m_(m), lda_(k + 1), ldc_(n + 2),
        a_(operand(v, static_cast<std::size_t>(m) * lda_, 11)),
        c0_(random_vector(static_cast<std::size_t>(m) * ldc_, 12)),
        bias_(random_vector(n, 13)), scale_(random_vector(n, 14)),
        w_(v, operand(v, static_cast<std::size_t>(n) * k, 15).data(), n, k) {}

  GemmEpilogue epilogue(float* c) const {
    GemmEpilogue ep;
    ep.bias = bias_.data();
    ep.act = Act::Gelu;
    ep.scale = scale_.data();
    ep.residual = c;
    ep.ldr = ldc_;
    return ep;
  }
  std::vector<float> fresh_c() const { return c0_; }
  const float* a_row(int i) const { return a_.data() + static_cast<std::size_t>(i) * lda_; }

  // gemm() over consecutive row ranges [bounds[i], bounds[i+1]).
  std::vector<float> by_rows(const std::vector<int>& bounds) const {
    std::vector<float> c = fresh_c();
    for (std::size_t i = 0; i + 1 < bounds.size(); ++i) {
      float* ci = c.data() + static_cast<std::size_t>(bounds[i]) * ldc_;
      w_.gemm(bounds[i + 1] - bounds[i], a_row(bounds[i]), lda_, ci, ldc_, epilogue(ci));
    }
    return c;
  }
  std::vector<float> parallel(int threads) const {
    std::vector<float> c = fresh_c();
    const nn::ExecScope threads_scope(nn::with_threads(threads));
    w_.gemm(m_, a_.data(), lda_, c.data(), ldc_, epilogue(c.data()), true);
    return c;
  }
  // gemm() on chunks of `rows` rows from inside a parallel loop of two threads.
  std::vector<float> inside_parallel_region(int rows) const {
    std::vector<float> c = fresh_c();
    const int chunks = (m_ + rows - 1) / rows;
    const nn::ExecScope threads_scope(nn::with_threads(2));
    nn::parallel_for(chunks, true, [&](long long i) {
      const int r0 = static_cast<int>(i) * rows, r1 = std::min(m_, r0 + rows);
      float* ci = c.data() + static_cast<std::size_t>(r0) * ldc_;
      w_.gemm(r1 - r0, a_row(r0), lda_, ci, ldc_, epilogue(ci));
    });
    return c;
  }
  // gemm_parallel() called by one thread of a parallel region runs on that thread alone.
  std::vector<float> parallel_inside_region() const {
    std::vector<float> c = fresh_c();
    const nn::ExecScope threads_scope(nn::with_threads(2));
    nn::parallel_team(2, [&](int id, int) {
      if (id == 0) w_.gemm(m_, a_.data(), lda_, c.data(), ldc_, epilogue(c.data()), true);
    });
    return c;
  }
  int m() const { return m_; }

 private:
  int m_;
  std::ptrdiff_t lda_, ldc_;
  std::vector<float> a_, c0_, bias_, scale_;
  PackedProduct w_;
};

void expect_same_bits(const std::vector<float>& x, const std::vector<float>& y, const char* what) {
  ASSERT_EQ(x.size(), y.size());
  EXPECT_EQ(0, std::memcmp(x.data(), y.data(), x.size() * sizeof(float))) << what;
}

// Any row split and any thread count give the same bits: each element sees the same
// FMA sequence and epilogue whichever tile (full or tail) computes it.
TEST_P(GemmUkernelTest, BitwiseIdenticalForAnySplit) {
  // Large M (row split), several row blocks with K blocks, small M (rows and panels
  // split), long K, and M a little above the 64-row threshold with many panels (columns
  // split; one tall row block per thread).
  const std::vector<DeterminismCase> full = {{203, 100, 96}, {150, 70, 700}, {50, 200, 1100}, {7, 130, 3100},
                                             {200, 400, 1100}};
  // The emulated run (ROADNN_TEST_SIZES=small): the same splits on shapes that still cross
  // the row blocks, K blocks, panels and the 64-row threshold, at a fiftieth of the work.
  const std::vector<DeterminismCase> small = {{203, 100, 96}, {7, 130, 700}, {70, 60, 300}};
  for (const auto& dc : reftest::small_sizes_only() ? small : full) {
    SCOPED_TRACE("m " + std::to_string(dc.m) + " n " + std::to_string(dc.n) + " k " +
                 std::to_string(dc.k));
    const AliasedProduct p(GetParam(), dc.m, dc.n, dc.k);
    const std::vector<float> whole = p.by_rows({0, p.m()});
    std::vector<int> odd = {0};
    for (int b : {1, 4, 9, 30, 45, 131})
      if (b < p.m()) odd.push_back(b);
    odd.push_back(p.m());
    expect_same_bits(whole, p.by_rows(odd), "rows split at odd offsets");
    std::vector<int> singles;
    for (int i = 0; i <= p.m(); ++i) singles.push_back(i);
    expect_same_bits(whole, p.by_rows(singles), "one row at a time");
    expect_same_bits(whole, p.parallel(1), "gemm_parallel, 1 thread");
    expect_same_bits(whole, p.parallel(2), "gemm_parallel, 2 threads");
    expect_same_bits(whole, p.parallel(3), "gemm_parallel, 3 threads");
    expect_same_bits(whole, p.inside_parallel_region(13), "gemm() inside a parallel region");
    expect_same_bits(whole, p.parallel_inside_region(), "gemm_parallel() inside a region");
  }
}

INSTANTIATE_TEST_SUITE_P(AllKernels, GemmUkernelTest, testing::ValuesIn(supported_variants()),
                         variant_test_name);

class GemmIsaTest : public testing::TestWithParam<nn::Isa> {};

// pack() picks the ISA's default kernel unless another of the ISA costs a tenth less
// for that N (nn/gemm_kernels.h), and gemm_kernel_name() names the kernel it picks.
TEST_P(GemmIsaTest, PackUsesTheIsaDefaultKernelUnlessAnotherIsCheaper) {
  const nn::Isa isa = GetParam();
  const int def = nn::gemm_default_ukernel(isa);
  const int def_nr = nn::gemm_ukernel(def).nr;
  for (int n : {16, 24, 40, def_nr, 3 * def_nr, 64, 112, 256, 1024, 4 * def_nr + 1}) {
    SCOPED_TRACE(n);
    const std::vector<float> w = random_vector(static_cast<std::size_t>(n) * 24, 3);
    const GemmWeights packed = GemmWeights::pack(w.data(), n, 24, isa);
    EXPECT_EQ(packed.isa(), isa);
    EXPECT_EQ(packed.n(), n);
    EXPECT_EQ(packed.k(), 24);
    const std::string name = nn::gemm_kernel_name(isa, n);
    EXPECT_EQ(name, nn::gemm_ukernel(packed.ukernel()).name);
    EXPECT_EQ(name.rfind("gemm_f32_", 0), 0u) << name;
    EXPECT_NE(name.find(nn::isa_name(isa)), std::string::npos) << name;
    const int nr = nn::gemm_ukernel(packed.ukernel()).nr;
    EXPECT_EQ(packed.bytes(), sizeof(float) * static_cast<std::size_t>((n + nr - 1) / nr) * nr * 24);
    EXPECT_EQ(nn::gemm_ukernel_for(isa, n), packed.ukernel());
  }
  if (isa == nn::Isa::Avx512) {
    EXPECT_STREQ(nn::gemm_kernel_name(isa, 384), "gemm_f32_8x48_avx512");  // ConvNeXt widths keep 8x48
    EXPECT_STREQ(nn::gemm_kernel_name(isa, 1024), "gemm_f32_8x48_avx512");  // 3 % padding: not worth a switch
    EXPECT_STREQ(nn::gemm_kernel_name(isa, 256), "gemm_f32_6x64_avx512");
    EXPECT_STREQ(nn::gemm_kernel_name(isa, 16), "gemm_f32_14x16_avx512");
    EXPECT_STREQ(nn::gemm_kernel_name(isa, 40), "gemm_f32_8x48_avx512");  // 14x16's 1.2 outweighs 8 columns
  }
  if (isa == nn::Isa::Avx2) {
    EXPECT_STREQ(nn::gemm_kernel_name(isa, 96), "gemm_f32_4x24_avx2");
    EXPECT_STREQ(nn::gemm_kernel_name(isa, 64), "gemm_f32_6x16_avx2");
  }
}

// The epilogue activation is the same vector routine as apply_act: same bits.
TEST_P(GemmIsaTest, EpilogueActivationMatchesApplyActBitwise) {
  const nn::Isa isa = GetParam();
  nntest::IsaScope scope(isa);
  const int m = 45, n = 77, k = 40;
  const std::vector<float> a = random_vector(static_cast<std::size_t>(m) * k, 21, -2.0f, 2.0f);
  const std::vector<float> w = random_vector(static_cast<std::size_t>(n) * k, 22);
  const std::vector<float> bias = random_vector(n, 23);
  const GemmWeights packed = GemmWeights::pack(w.data(), n, k, isa);
  for (Act act : kActs) {
    SCOPED_TRACE(static_cast<int>(act));
    GemmEpilogue plain;
    plain.bias = bias.data();
    GemmEpilogue fused = plain;
    fused.act = act;
    std::vector<float> x(static_cast<std::size_t>(m) * n), y(x.size());
    nn::gemm(m, a.data(), k, packed, x.data(), n, plain);
    nn::apply_act(act, x.data(), x.size());
    nn::gemm(m, a.data(), k, packed, y.data(), n, fused);
    expect_same_bits(x, y, "gemm epilogue vs apply_act");
  }
}

INSTANTIATE_TEST_SUITE_P(AllIsas, GemmIsaTest, testing::ValuesIn(nntest::supported_isas()),
                         nntest::isa_test_name);

TEST(GemmErrors, BadShapesAndStridesThrow) {
  const std::vector<float> w(64, 1.0f), a(64, 1.0f);
  std::vector<float> c(64);
  EXPECT_THROW(GemmWeights::pack(w.data(), 0, 4), nn::Error);
  EXPECT_THROW(GemmWeights::pack(w.data(), 4, 0), nn::Error);
  EXPECT_THROW(GemmWeights::pack(w.data(), -3, 4), nn::Error);
  EXPECT_THROW(GemmWeights::pack(nullptr, 4, 4), nn::Error);
  EXPECT_THROW(GemmWeights::pack_for_ukernel(w.data(), 4, 4, -1), nn::Error);
  EXPECT_THROW(GemmWeights::pack_for_ukernel(w.data(), 4, 4, nn::gemm_ukernel_count()), nn::Error);
  const GemmWeights empty;
  EXPECT_THROW(nn::gemm(1, a.data(), 4, empty, c.data(), 4), nn::Error);
  const GemmWeights packed = GemmWeights::pack(w.data(), 4, 8);
  EXPECT_THROW(nn::gemm(2, a.data(), 7, packed, c.data(), 4), nn::Error);   // lda < K
  EXPECT_THROW(nn::gemm(2, a.data(), 8, packed, c.data(), 3), nn::Error);   // ldc < N
  EXPECT_THROW(nn::gemm(-1, a.data(), 8, packed, c.data(), 4), nn::Error);
  GemmEpilogue ep;
  ep.residual = c.data();
  ep.ldr = 2;
  EXPECT_THROW(nn::gemm(2, a.data(), 8, packed, c.data(), 4, ep), nn::Error);  // ldr < N
  EXPECT_THROW(nn::gemm_parallel(2, a.data(), 8, packed, c.data(), 3), nn::Error);
  GemmEpilogue bad_act;
  bad_act.act = static_cast<Act>(17);
  EXPECT_THROW(nn::gemm(2, a.data(), 8, packed, c.data(), 4, bad_act), nn::Error);
  EXPECT_NO_THROW(nn::gemm(0, a.data(), 8, packed, c.data(), 4));
}

TEST(GemmRef, SmallProductByHand) {
  // A [2 x 3], W [2 x 3]: C = A W^T, then bias, ReLU, scale, residual.
  const float a[] = {1, 2, 3, -1, 0.5f, 2};
  const float w[] = {1, 0, -1, 2, 1, 0.5f};
  const float bias[] = {0.5f, -1};
  const float scale[] = {2, 3};
  const float res[] = {10, 20, 30, 40};
  float c[4];
  GemmEpilogue ep;
  ep.bias = bias;
  ep.act = Act::Relu;
  ep.scale = scale;
  ep.residual = res;
  ep.ldr = 2;
  nn::gemm_ref(2, 2, 3, a, 3, w, c, 2, ep);
  // raw: [1-3, 2+2+1.5; -1-2, -2+0.5+1] = [-2, 5.5; -3, -0.5]
  EXPECT_FLOAT_EQ(c[0], 10.0f);             // relu(-1.5) * 2 + 10
  EXPECT_FLOAT_EQ(c[1], 4.5f * 3 + 20);     // relu(4.5) * 3 + 20
  EXPECT_FLOAT_EQ(c[2], 30.0f);             // relu(-2.5) * 2 + 30
  EXPECT_FLOAT_EQ(c[3], 40.0f);             // relu(-1.5) * 3 + 40
  ep.act_after_residual = true;
  ep.act = Act::Relu;
  const float neg_res[] = {-10, 0, 0, 0};
  ep.residual = neg_res;
  nn::gemm_ref(2, 2, 3, a, 3, w, c, 2, ep);
  EXPECT_FLOAT_EQ(c[0], 0.0f);              // relu(-1.5 * 2 - 10)
  EXPECT_FLOAT_EQ(c[1], 4.5f * 3);
}

}  // namespace
