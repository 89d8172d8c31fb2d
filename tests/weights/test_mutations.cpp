// Randomly damaged inputs (fixed seed, so failures reproduce): the parsers must
// either accept or throw their own error type, never crash or throw anything
// else. Most useful under -fsanitize=address,undefined.
#include <gtest/gtest.h>

#include <random>
#include <string>

#include "weights/json.h"
#include "weights/safetensors.h"
#include "weights/tensor_spec.h"

namespace {

std::vector<std::uint8_t> damage(std::vector<std::uint8_t> bytes, std::mt19937& rng) {
  std::uniform_int_distribution<int> kind(0, 3);
  std::uniform_int_distribution<int> byte(0, 255);
  const int edits = 1 + static_cast<int>(rng() % 3);
  for (int e = 0; e < edits && !bytes.empty(); ++e) {
    std::size_t at = rng() % bytes.size();
    switch (kind(rng)) {
      case 0: bytes[at] = static_cast<std::uint8_t>(byte(rng)); break;
      case 1: bytes[at] ^= static_cast<std::uint8_t>(1u << (rng() % 8)); break;
      case 2: bytes.resize(at); break;
      default: bytes.insert(bytes.begin() + at, static_cast<std::uint8_t>(byte(rng))); break;
    }
  }
  return bytes;
}

TEST(Mutations, DamagedSafetensorsNeverCrash) {
  std::vector<float> a(24);
  for (std::size_t i = 0; i < a.size(); ++i) a[i] = 0.5f * static_cast<float>(i);
  const std::int64_t idx[3] = {1, 2, 3};
  const std::uint16_t half[4] = {0x3C00, 0x4000, 0x7BFF, 0x0001};
  weights::Writer w;
  w.set_metadata("format", "roadnn-v1");
  w.add_f32("stem.weight", {2, 3, 2, 2}, a.data());
  w.add_i64("index", {3}, idx);
  w.add("half", weights::DType::F16, {2, 2}, half);
  w.add_f32("empty", {0}, nullptr);
  const std::vector<std::uint8_t> good = w.bytes();

  std::mt19937 rng(12345);
  int accepted = 0;
  for (int iter = 0; iter < 20000; ++iter) {
    std::vector<std::uint8_t> bad = damage(good, rng);
    try {
      weights::SafeTensors st = weights::SafeTensors::from_bytes(bad, "fuzz");
      ++accepted;
      for (const std::string& name : st.names()) {
        const weights::TensorInfo& t = st.info(name);
        if (weights::is_float_dtype(t.dtype)) {
          EXPECT_EQ(st.f32(name).size(), static_cast<std::size_t>(t.numel()));
          weights::check_tensors(st, {{name, t.shape}});
        }
      }
    } catch (const weights::Error&) {
      // expected for nearly every mutation
    }
  }
  // Flips inside tensor data or header padding keep the file valid.
  EXPECT_GT(accepted, 0);
  EXPECT_LT(accepted, 20000);
}

TEST(Mutations, DamagedJsonNeverCrashes) {
  const std::string doc =
      "{\"version\": \"5.0.1\", \"flags\": {}, \"shapes\": [{\"label\": \"caf\xC3\xA9\", "
      "\"points\": [[1.5, -2e3], [0, 4]], \"group_id\": null, \"esc\": \"a\\n\\u00e9\\ud83d\\ude00\"}], "
      "\"ok\": true, \"big\": 18446744073709551615}";
  ASSERT_NO_THROW(json::parse(doc, "fuzz"));
  const std::vector<std::uint8_t> good(doc.begin(), doc.end());
  std::mt19937 rng(777);
  int accepted = 0;
  for (int iter = 0; iter < 20000; ++iter) {
    std::vector<std::uint8_t> bad = damage(good, rng);
    try {
      json::parse(std::string_view(reinterpret_cast<const char*>(bad.data()), bad.size()), "fuzz");
      ++accepted;
    } catch (const json::Error& e) {
      EXPECT_EQ(std::string(e.what()).rfind("fuzz: line ", 0), 0u) << e.what();
    }
  }
  EXPECT_GT(accepted, 0);
  EXPECT_LT(accepted, 20000);
}

}  // namespace
