// The bf16 GEMM's own pieces: float -> bfloat16 rounding (the reference conversion and the
// vector one, bitwise), packing and argument errors, and its refusal on CPUs or forced ISAs
// without AVX512_BF16. Its products are checked with every other kernel in test_gemm.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "nn/error.h"
#include "nn/gemm_bf16.h"
#include "nn/isa.h"
#include "tests/error_of.h"

namespace {

using nn::bf16;

float from_bits(std::uint32_t u) {
  float f;
  std::memcpy(&f, &u, 4);
  return f;
}

TEST(Bf16Rounding, NearestEvenAndSpecialValues) {
  EXPECT_EQ(nn::f32_to_bf16(1.0f), 0x3F80);
  EXPECT_EQ(nn::f32_to_bf16(-2.0f), 0xC000);
  EXPECT_EQ(nn::f32_to_bf16(0.0f), 0x0000);
  EXPECT_EQ(nn::f32_to_bf16(-0.0f), 0x8000);
  // 1 + 2^-8 lies halfway between 1 and 1 + 2^-7: ties go to the even mantissa (1).
  EXPECT_EQ(nn::f32_to_bf16(from_bits(0x3F808000u)), 0x3F80);
  // 1 + 3 * 2^-8 is halfway between 1 + 2^-7 (odd) and 1 + 2^-6 (even): rounds up.
  EXPECT_EQ(nn::f32_to_bf16(from_bits(0x3F818000u)), 0x3F82);
  EXPECT_EQ(nn::f32_to_bf16(from_bits(0x3F807FFFu)), 0x3F80);  // just below the tie
  EXPECT_EQ(nn::f32_to_bf16(from_bits(0x3F808001u)), 0x3F81);  // just above
  EXPECT_EQ(nn::f32_to_bf16(std::numeric_limits<float>::max()), 0x7F80);  // rounds to inf
  EXPECT_EQ(nn::f32_to_bf16(std::numeric_limits<float>::infinity()), 0x7F80);
  EXPECT_EQ(nn::f32_to_bf16(-std::numeric_limits<float>::infinity()), 0xFF80);
  const bf16 nan = nn::f32_to_bf16(std::numeric_limits<float>::quiet_NaN());
  EXPECT_TRUE(std::isnan(nn::bf16_to_f32(nan)));
  EXPECT_TRUE(std::isnan(nn::bf16_to_f32(nn::f32_to_bf16(from_bits(0x7F800001u)))))  // signalling
      << "a NaN whose payload sits in the low bits must not become inf";
  EXPECT_EQ(nn::f32_to_bf16(from_bits(0x00000001u)), 0x0000);  // denormals flush, sign kept
  EXPECT_EQ(nn::f32_to_bf16(from_bits(0x807FFFFFu)), 0x8000);
  EXPECT_EQ(nn::bf16_to_f32(0x4049), 3.140625f);
}

// The vector conversion (AVX512_BF16) gives the reference's bits, including NaN,
// infinities, denormals and ties; odd widths get their zero pad, nothing past it is written.
TEST(Bf16Rounding, ConvertEqualsTheReferenceBitwise) {
  std::mt19937 gen(5);
  std::uniform_int_distribution<std::uint32_t> bits;
  std::uniform_real_distribution<float> val(-10.0f, 10.0f);
  for (int cols : {1, 3, 16, 17, 33, 95, 96}) {
    SCOPED_TRACE(cols);
    const int rows = 5;
    const std::ptrdiff_t lds = cols + 3, ldd = cols + (cols & 1) + 4;
    std::vector<float> src(static_cast<std::size_t>(rows) * lds);
    for (std::size_t i = 0; i < src.size(); ++i)
      src[i] = i % 3 == 0 ? from_bits(bits(gen)) : i % 3 == 1 ? val(gen) : from_bits(0x3F808000u + (i & 0x10000u));
    const std::uint32_t specials[] = {0x00000001u, 0x807FFFFFu, 0x7F800000u, 0xFF800000u,
                                      0x7FC00000u, 0x7F800001u, 0xFFFFFFFFu, 0x7F7FFFFFu};
    for (std::size_t i = 0; i < 8 && i * 7 < src.size(); ++i) src[i * 7] = from_bits(specials[i]);
    std::vector<bf16> dst(static_cast<std::size_t>(rows) * ldd, 0xABCD);
    nn::convert_to_bf16(rows, cols, src.data(), lds, dst.data(), ldd);
    for (int r = 0; r < rows; ++r) {
      for (int j = 0; j < cols; ++j)
        ASSERT_EQ(dst[r * ldd + j], nn::f32_to_bf16(src[r * lds + j])) << "row " << r << " col " << j;
      int j = cols;
      if (cols & 1) {
        EXPECT_EQ(dst[r * ldd + j], 0) << "pad of row " << r;
        ++j;
      }
      for (; j < ldd; ++j) EXPECT_EQ(dst[r * ldd + j], 0xABCD) << "wrote past row " << r;
    }
  }
}

TEST(Bf16Gemm, ArgumentErrors) {
  if (!nn::bf16_gemm_available()) GTEST_SKIP() << "this CPU has no AVX512_BF16";
  const std::vector<float> w(64, 1.0f);
  EXPECT_THROW(nn::GemmWeightsBf16::pack(w.data(), 0, 4), nn::Error);
  EXPECT_THROW(nn::GemmWeightsBf16::pack(nullptr, 4, 4), nn::Error);
  const nn::GemmWeightsBf16 packed = nn::GemmWeightsBf16::pack(w.data(), 4, 7);  // K pads to 8
  EXPECT_EQ(packed.k(), 7);
  EXPECT_EQ(packed.bytes(), sizeof(float) * 48 * 4);  // one panel of 4 K pairs
  std::vector<bf16> a(64, 0);
  std::vector<float> c(64);
  EXPECT_THROW(nn::gemm_bf16(2, a.data(), 7, packed, c.data(), 4), nn::Error);  // odd lda
  EXPECT_THROW(nn::gemm_bf16(2, a.data(), 6, packed, c.data(), 4), nn::Error);  // lda < 8
  EXPECT_THROW(nn::gemm_bf16(2, a.data(), 8, packed, c.data(), 3), nn::Error);  // ldc < N
  EXPECT_THROW(nn::gemm_bf16(-1, a.data(), 8, packed, c.data(), 4), nn::Error);
  EXPECT_THROW(nn::gemm_bf16(1, a.data(), 8, nn::GemmWeightsBf16(), c.data(), 4), nn::Error);
  EXPECT_NO_THROW(nn::gemm_bf16(0, a.data(), 8, packed, c.data(), 4));
}

// Forcing the kernels below AVX-512 turns the bf16 GEMM off with a clear message.
TEST(Bf16Gemm, RefusedBelowAvx512) {
  const nn::Isa saved = nn::active_isa();
  nn::set_isa(nn::Isa::Avx2);
  EXPECT_FALSE(nn::bf16_gemm_available());
  const std::vector<float> w(16, 1.0f);
  const std::string err = testutil::error_of([&] { nn::GemmWeightsBf16::pack(w.data(), 4, 4); });
  nn::set_isa(saved);
  EXPECT_NE(err.find("no AVX512_BF16"), std::string::npos) << err;
}

}  // namespace
