// The C++ reader on a file written by weights/safetensors_io.py (fixture
// ref_weights_python runs tests/weights/write_python_safetensors.py first).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>

#include "weights/safetensors.h"

namespace {

const std::string kPath = std::string(ROADNN_REF_DIR) + "/weights_python.safetensors";

TEST(PythonWrittenFile, ValuesMatch) {
  weights::SafeTensors st = weights::SafeTensors::load(kPath);
  EXPECT_EQ(st.names(), (std::vector<std::string>{"f32", "f16", "bf16", "i64", "i32", "u8", "scalar",
                                                  "empty", "big_endian", "torch_f32"}));
  EXPECT_EQ(st.metadata().at("format"), "roadnn-v1");
  EXPECT_EQ(st.metadata().at("writer"), "safetensors_io.py");
  EXPECT_EQ(st.metadata().at("unicode"), "stra\xC3\x9F" "e");

  ASSERT_EQ(st.info("f32").shape, (std::vector<std::int64_t>{2, 3, 4}));
  std::vector<float> f32 = st.f32("f32");
  for (int i = 0; i < 24; ++i) EXPECT_EQ(f32[i], static_cast<float>(i) * 0.25f - 1.0f) << i;

  EXPECT_EQ(st.info("f16").dtype, weights::DType::F16);
  EXPECT_EQ(st.f32("f16"), (std::vector<float>{1.0f, -2.0f, 65504.0f, std::ldexp(1.0f, -24),
                                               0.0999755859375f}));

  EXPECT_EQ(st.info("bf16").dtype, weights::DType::BF16);
  std::vector<float> bf = st.f32("bf16");
  ASSERT_EQ(bf.size(), 4u);
  EXPECT_EQ(bf[0], 1.0f);
  EXPECT_EQ(bf[1], -3.0f);
  EXPECT_EQ(bf[2], 0.10009765625f);  // torch rounds 0.1 to the nearest bfloat16
  EXPECT_EQ(bf[3], weights::bf16_to_f32(0x7F62));

  EXPECT_EQ(st.i64("i64"), (std::vector<std::int64_t>{-(1ll << 62), 0, 7}));
  EXPECT_EQ(st.info("i32").shape, (std::vector<std::int64_t>{1, 2}));
  EXPECT_EQ(st.i64("i32"), (std::vector<std::int64_t>{-5, 6}));
  EXPECT_EQ(st.info("u8").dtype, weights::DType::U8);
  EXPECT_EQ(std::memcmp(st.raw("u8"), "\x00\x01\x02\x03\x04", 5), 0);
  EXPECT_TRUE(st.info("scalar").shape.empty());
  EXPECT_EQ(st.f32("scalar"), std::vector<float>{3.5f});
  EXPECT_EQ(st.info("empty").shape, (std::vector<std::int64_t>{0, 4}));
  EXPECT_TRUE(st.f32("empty").empty());
  EXPECT_EQ(st.f32("big_endian"), (std::vector<float>{0, 1, 2, 3}));
  EXPECT_EQ(st.f32("torch_f32"), (std::vector<float>{-1.0f, -0.5f, 0.0f, 0.5f, 1.0f}));
}

TEST(PythonWrittenFile, DataSectionIs64ByteAligned) {
  std::FILE* f = std::fopen(kPath.c_str(), "rb");
  ASSERT_NE(f, nullptr);
  unsigned char len[8];
  ASSERT_EQ(std::fread(len, 1, 8, f), 8u);
  std::fclose(f);
  std::uint64_t n = 0;
  for (int i = 7; i >= 0; --i) n = (n << 8) | len[i];
  EXPECT_EQ((8 + n) % 64, 0u);
}

}  // namespace
