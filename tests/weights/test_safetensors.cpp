// Safetensors in memory: Writer -> reader round trips, exact widening of half
// types, value accessors and the Writer's own input checks.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "tests/weights/safetensors_bytes.h"
#include "weights/safetensors.h"

namespace {

using weights::DType;
using weights::SafeTensors;
using weights::Writer;

std::uint32_t bits_of(float f) {
  std::uint32_t b;
  std::memcpy(&b, &f, 4);
  return b;
}

std::uint64_t header_length(const std::vector<std::uint8_t>& bytes) {
  std::uint64_t n = 0;
  for (int i = 7; i >= 0; --i) n = (n << 8) | bytes[i];
  return n;
}

TEST(SafeTensors, RoundTripsF32I64MetadataEmptyAndScalar) {
  const float a[6] = {1.5f, -2.0f, 0.0f, 3.25f, 1e-30f, -7.0f};
  const std::int64_t b[4] = {-1, 0, 1ll << 60, 42};
  const float s = 9.75f;
  Writer w;
  w.set_metadata("format", "roadnn-v1");
  w.set_metadata("note", "caf\xC3\xA9 \"quoted\"\n");
  w.add_f32("a", {2, 3}, a);
  w.add_i64("b", {4}, b);
  w.add_f32("empty", {0, 5}, nullptr);
  w.add_f32("scalar", {}, &s);
  std::vector<std::uint8_t> bytes = w.bytes();
  EXPECT_EQ((8 + header_length(bytes)) % 64, 0u) << "data section must start 64-byte aligned";

  SafeTensors st = SafeTensors::from_bytes(bytes, "mem");
  EXPECT_EQ(st.source(), "mem");
  EXPECT_EQ(st.names(), (std::vector<std::string>{"a", "b", "empty", "scalar"}));
  EXPECT_EQ(st.metadata().size(), 2u);
  EXPECT_EQ(st.metadata().at("format"), "roadnn-v1");
  EXPECT_EQ(st.metadata().at("note"), "caf\xC3\xA9 \"quoted\"\n");

  EXPECT_EQ(st.info("a").dtype, DType::F32);
  EXPECT_EQ(st.info("a").shape, (std::vector<std::int64_t>{2, 3}));
  EXPECT_EQ(st.info("a").numel(), 6);
  EXPECT_EQ(st.f32("a"), std::vector<float>(a, a + 6));
  EXPECT_EQ(st.info("b").dtype, DType::I64);
  EXPECT_EQ(st.i64("b"), std::vector<std::int64_t>(b, b + 4));
  EXPECT_EQ(st.info("empty").numel(), 0);
  EXPECT_TRUE(st.f32("empty").empty());
  EXPECT_TRUE(st.info("scalar").shape.empty());
  EXPECT_EQ(st.info("scalar").numel(), 1);
  EXPECT_EQ(st.f32("scalar"), std::vector<float>{9.75f});

  float first;
  std::memcpy(&first, st.raw("a"), 4);
  EXPECT_EQ(first, 1.5f);
  EXPECT_EQ(st.info("b").end - st.info("b").begin, 32u);
}

TEST(SafeTensors, NamesFollowFileOrderNotAlphabet) {
  const float v[2] = {1, 2};
  Writer w;
  w.add_f32("zeta", {1}, v);
  w.add_f32("alpha", {2}, v);
  w.add_f32("mid", {1}, v + 1);
  SafeTensors st = SafeTensors::from_bytes(w.bytes(), "mem");
  EXPECT_EQ(st.names(), (std::vector<std::string>{"zeta", "alpha", "mid"}));
  EXPECT_EQ(st.f32("mid"), std::vector<float>{2});
  EXPECT_TRUE(st.metadata().empty());
}

TEST(SafeTensors, HeaderOrderDoesNotMatterOffsetsDo) {
  // Header lists b first, but a's data comes first in the file.
  auto bytes = weights_test::file_bytes(
      R"({"b":{"dtype":"U8","shape":[2],"data_offsets":[2,4]},)"
      R"("a":{"dtype":"U8","shape":[2],"data_offsets":[0,2]}})",
      4);
  SafeTensors st = SafeTensors::from_bytes(bytes, "mem");
  EXPECT_EQ(st.names(), (std::vector<std::string>{"a", "b"}));
  EXPECT_EQ(st.raw("b")[0], 2);
}

TEST(SafeTensors, F16WideningIsExact) {
  const std::uint16_t half[] = {0x3C00, 0xC000, 0x7BFF, 0x0001, 0x03FF, 0x0400,
                                0x8000, 0x7C00, 0xFC00, 0x3555, 0x8001, 0x7E01};
  Writer w;
  w.add("h", DType::F16, {12}, half);
  SafeTensors st = SafeTensors::from_bytes(w.bytes(), "mem");
  std::vector<float> f = st.f32("h");
  ASSERT_EQ(f.size(), 12u);
  EXPECT_EQ(f[0], 1.0f);
  EXPECT_EQ(f[1], -2.0f);
  EXPECT_EQ(f[2], 65504.0f);
  EXPECT_EQ(f[3], std::ldexp(1.0f, -24));          // smallest subnormal
  EXPECT_EQ(f[4], std::ldexp(1023.0f, -24));       // largest subnormal
  EXPECT_EQ(f[5], std::ldexp(1.0f, -14));          // smallest normal
  EXPECT_EQ(bits_of(f[6]), 0x80000000u);           // -0 keeps its sign
  EXPECT_EQ(f[7], std::numeric_limits<float>::infinity());
  EXPECT_EQ(f[8], -std::numeric_limits<float>::infinity());
  EXPECT_EQ(f[9], 0.333251953125f);
  EXPECT_EQ(f[10], -std::ldexp(1.0f, -24));
  EXPECT_TRUE(std::isnan(f[11]));
  EXPECT_EQ(bits_of(f[11]), 0x7FC02000u);          // payload kept
}

TEST(SafeTensors, F16WideningMatchesTheDefinitionForEveryPattern) {
  for (std::uint32_t h = 0; h < 0x10000; ++h) {
    int exp = (h >> 10) & 0x1F;
    int mant = h & 0x3FF;
    float sign = (h & 0x8000) ? -1.0f : 1.0f;
    float got = weights::f16_to_f32(static_cast<std::uint16_t>(h));
    if (exp == 31) {
      EXPECT_EQ(std::isnan(got), mant != 0) << h;
      continue;
    }
    float want = exp == 0 ? sign * std::ldexp(static_cast<float>(mant), -24)
                          : sign * std::ldexp(static_cast<float>(1024 + mant), exp - 25);
    ASSERT_EQ(bits_of(got), bits_of(want)) << "half bits " << h;
  }
}

TEST(SafeTensors, BF16WideningIsExact) {
  const std::uint16_t bf[] = {0x3F80, 0xC040, 0x7F7F, 0x0001, 0xFF80, 0x7FC1};
  Writer w;
  w.add("b", DType::BF16, {2, 3}, bf);
  SafeTensors st = SafeTensors::from_bytes(w.bytes(), "mem");
  std::vector<float> f = st.f32("b");
  ASSERT_EQ(f.size(), 6u);
  EXPECT_EQ(f[0], 1.0f);
  EXPECT_EQ(f[1], -3.0f);
  EXPECT_EQ(f[2], 3.3895313892515355e38f);
  for (int i = 0; i < 6; ++i) EXPECT_EQ(bits_of(f[i]), static_cast<std::uint32_t>(bf[i]) << 16);
  EXPECT_TRUE(std::isinf(f[4]));
  EXPECT_TRUE(std::isnan(f[5]));
}

TEST(SafeTensors, I32WidensToI64) {
  const std::int32_t v[3] = {-2147483647 - 1, 5, 2147483647};
  Writer w;
  w.add("i", DType::I32, {3}, v);
  SafeTensors st = SafeTensors::from_bytes(w.bytes(), "mem");
  EXPECT_EQ(st.i64("i"), (std::vector<std::int64_t>{-2147483648ll, 5, 2147483647}));
}

TEST(SafeTensors, AccessorsRejectTheWrongDtype) {
  const std::int64_t i[1] = {1};
  const float f[1] = {1};
  const std::uint8_t u[1] = {1};
  Writer w;
  w.add_i64("ints", {1}, i);
  w.add_f32("floats", {1}, f);
  w.add("bytes", DType::U8, {1}, u);
  SafeTensors st = SafeTensors::from_bytes(w.bytes(), "m.safetensors");
  try {
    st.f32("ints");
    FAIL() << "f32 accepted an I64 tensor";
  } catch (const weights::Error& e) {
    EXPECT_STREQ(e.what(),
                 "m.safetensors: tensor 'ints' has dtype I64, expected a float type (F32, F16 or BF16)");
  }
  try {
    st.i64("floats");
    FAIL() << "i64 accepted an F32 tensor";
  } catch (const weights::Error& e) {
    EXPECT_STREQ(e.what(),
                 "m.safetensors: tensor 'floats' has dtype F32, expected an integer type (I64 or I32)");
  }
  EXPECT_THROW(st.f32("bytes"), weights::Error);
  EXPECT_THROW(st.i64("bytes"), weights::Error);
}

TEST(SafeTensors, MissingTensorIsNamed) {
  Writer w;
  SafeTensors st = SafeTensors::from_bytes(w.bytes(), "m.safetensors");
  EXPECT_FALSE(st.has("nope"));
  EXPECT_TRUE(st.names().empty());
  try {
    st.info("nope");
    FAIL();
  } catch (const weights::Error& e) {
    EXPECT_STREQ(e.what(), "m.safetensors: no tensor 'nope'");
  }
  EXPECT_THROW(st.f32("nope"), weights::Error);
  EXPECT_THROW(st.raw("nope"), weights::Error);
}

TEST(SafeTensors, DtypeNamesAndSizes) {
  const std::pair<DType, std::pair<const char*, std::size_t>> all[] = {
      {DType::F64, {"F64", 8}}, {DType::F32, {"F32", 4}}, {DType::F16, {"F16", 2}},
      {DType::BF16, {"BF16", 2}}, {DType::I64, {"I64", 8}}, {DType::I32, {"I32", 4}},
      {DType::I16, {"I16", 2}}, {DType::I8, {"I8", 1}}, {DType::U8, {"U8", 1}},
      {DType::BOOL, {"BOOL", 1}}};
  for (const auto& [dtype, expect] : all) {
    EXPECT_STREQ(weights::dtype_name(dtype), expect.first);
    EXPECT_EQ(weights::dtype_size(dtype), expect.second);
    // Every dtype survives a write/read round trip.
    std::vector<std::uint8_t> data(2 * expect.second, 0x11);
    Writer w;
    w.add("t", dtype, {2}, data.data());
    SafeTensors st = SafeTensors::from_bytes(w.bytes(), "mem");
    EXPECT_EQ(st.info("t").dtype, dtype);
    EXPECT_EQ(std::memcmp(st.raw("t"), data.data(), data.size()), 0);
  }
}

TEST(SafeTensors, ShapeStr) {
  EXPECT_EQ(weights::shape_str({96, 3, 4, 4}), "[96, 3, 4, 4]");
  EXPECT_EQ(weights::shape_str({}), "[]");
  EXPECT_EQ(weights::shape_str({0}), "[0]");
}

TEST(Writer, RejectsBadNamesAndShapes) {
  const float v[1] = {0};
  Writer w;
  w.add_f32("x", {1}, v);
  auto message = [&](auto&& f) -> std::string {
    try {
      f();
    } catch (const weights::Error& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(message([&] { w.add_f32("x", {1}, v); }).find("'x' added twice"), std::string::npos);
  EXPECT_NE(message([&] { w.add_f32("", {1}, v); }).find("empty tensor name"), std::string::npos);
  EXPECT_NE(message([&] { w.add_f32("__metadata__", {1}, v); }).find("reserved"), std::string::npos);
  EXPECT_NE(message([&] { w.add_f32("__pad__0", {1}, v); }).find("reserved"), std::string::npos);
  EXPECT_NE(message([&] { w.add_f32("bad\xFF", {1}, v); }).find("not valid UTF-8"), std::string::npos);
  EXPECT_NE(message([&] { w.add_f32("neg", {2, -1}, v); }).find("negative dimension"),
            std::string::npos);
  EXPECT_NE(message([&] { w.add_f32("r9", std::vector<std::int64_t>(9, 1), v); }).find("rank 9"),
            std::string::npos);
  EXPECT_NE(message([&] { w.add_f32("huge", {1ll << 40, 1ll << 40}, v); }).find("too large"),
            std::string::npos);
  EXPECT_NE(message([&] { w.add_f32("null", {3}, nullptr); }).find("no data"), std::string::npos);
  EXPECT_NE(message([&] { w.set_metadata("k", "\xC3"); }).find("not valid UTF-8"), std::string::npos);
  // Failed adds leave the writer usable and unchanged.
  SafeTensors st = SafeTensors::from_bytes(w.bytes(), "mem");
  EXPECT_EQ(st.names(), std::vector<std::string>{"x"});
}

TEST(Writer, MetadataKeysAreSetNotAppended) {
  Writer w;
  w.set_metadata("k", "1");
  w.set_metadata("k", "2");
  SafeTensors st = SafeTensors::from_bytes(w.bytes(), "mem");
  EXPECT_EQ(st.metadata().at("k"), "2");
}

TEST(Writer, OutputIsDeterministic) {
  const float v[3] = {1, 2, 3};
  auto make = [&] {
    Writer w;
    w.set_metadata("b", "2");
    w.set_metadata("a", "1");
    w.add_f32("t", {3}, v);
    return w.bytes();
  };
  EXPECT_EQ(make(), make());
}

}  // namespace

// Issue 12, finding 4: an empty tensor whose other dimensions multiply past int64
// (valid: zero elements) must not overflow in numel().
TEST(SafeTensors, NumelOfAnEmptyTensorWithHugeDimensionsIsZero) {
  weights::TensorInfo t;
  t.shape = {std::int64_t{1} << 32, std::int64_t{1} << 32, 0};
  EXPECT_EQ(0, t.numel());
  t.shape = {0, std::int64_t{1} << 40, std::int64_t{1} << 40};
  EXPECT_EQ(0, t.numel());
  t.shape = {3, 4};
  EXPECT_EQ(12, t.numel());
}

// Found by scripts/sanitize (UBSan): the test above overflowed int64 before reaching
// the zero; a non-empty shape past int64 is an error, not undefined behaviour.
TEST(SafeTensors, NumelPastInt64IsAnError) {
  weights::TensorInfo t;
  t.name = "big";
  t.shape = {std::int64_t{1} << 32, std::int64_t{1} << 32};
  EXPECT_THROW(t.numel(), weights::Error);
  t.shape = {std::int64_t{1} << 31, std::int64_t{1} << 31};
  EXPECT_EQ(std::int64_t{1} << 62, t.numel());
}
