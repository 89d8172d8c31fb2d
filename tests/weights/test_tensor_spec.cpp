// check_tensors: the first problem is reported with the file and tensor named;
// tensors nobody asked for are returned, never dropped silently.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "tests/weights/safetensors_bytes.h"
#include "weights/tensor_spec.h"

namespace {

using weights::SafeTensors;
using weights::TensorSpec;
using weights::Writer;

std::string check_error(const SafeTensors& st, const std::vector<TensorSpec>& specs) {
  try {
    weights::check_tensors(st, specs);
  } catch (const weights::Error& e) {
    return e.what();
  }
  return "";
}

SafeTensors convnext_like(float poison = 0.0f, int poison_at = -1) {
  std::vector<float> stem(96 * 3 * 3 * 3, 0.5f);
  std::vector<float> bias(96, 0.25f);
  if (poison_at >= 0) bias[poison_at] = poison;
  std::vector<float> dw(96 * 49, -1.0f);
  Writer w;
  w.add_f32("features.0.0.weight", {96, 3, 3, 3}, stem.data());
  w.add_f32("features.0.0.bias", {96}, bias.data());
  w.add_f32("features.1.0.block.0.weight", {96, 1, 7, 7}, dw.data());
  return SafeTensors::from_bytes(w.bytes(), "w.safetensors");
}

TEST(CheckTensors, AllPresentReturnsNothingUnused) {
  SafeTensors st = convnext_like();
  EXPECT_TRUE(weights::check_tensors(st, {{"features.0.0.weight", {96, 3, 3, 3}},
                                          {"features.0.0.bias", {96}},
                                          {"features.1.0.block.0.weight", {96, 1, 7, 7}}})
                  .empty());
}

TEST(CheckTensors, MissingTensor) {
  SafeTensors st = convnext_like();
  EXPECT_EQ(check_error(st, {{"features.0.0.bias", {96}}, {"features.1.0.block.3.weight", {96, 1, 7, 7}}}),
            "w.safetensors: missing tensor 'features.1.0.block.3.weight' (expected shape [96, 1, 7, 7])");
}

TEST(CheckTensors, WrongShape) {
  SafeTensors st = convnext_like();
  EXPECT_EQ(check_error(st, {{"features.0.0.weight", {96, 3, 4, 4}}}),
            "w.safetensors: tensor 'features.0.0.weight' has shape [96, 3, 3, 3], expected [96, 3, 4, 4]");
  // Same element count, different rank: still wrong.
  EXPECT_EQ(check_error(st, {{"features.0.0.bias", {96, 1}}}),
            "w.safetensors: tensor 'features.0.0.bias' has shape [96], expected [96, 1]");
}

TEST(CheckTensors, NaN) {
  SafeTensors st = convnext_like(std::numeric_limits<float>::quiet_NaN(), 17);
  EXPECT_EQ(check_error(st, {{"features.0.0.bias", {96}}}),
            "w.safetensors: tensor 'features.0.0.bias' contains NaN (element 17)");
}

TEST(CheckTensors, Inf) {
  EXPECT_EQ(check_error(convnext_like(std::numeric_limits<float>::infinity(), 95),
                        {{"features.0.0.bias", {96}}}),
            "w.safetensors: tensor 'features.0.0.bias' contains Inf (element 95)");
  EXPECT_EQ(check_error(convnext_like(-std::numeric_limits<float>::infinity(), 0),
                        {{"features.0.0.bias", {96}}}),
            "w.safetensors: tensor 'features.0.0.bias' contains Inf (element 0)");
}

TEST(CheckTensors, LargestFiniteValuesPass) {
  SafeTensors st = convnext_like(std::numeric_limits<float>::max(), 3);
  EXPECT_EQ(check_error(st, {{"features.0.0.bias", {96}}}), "");
}

TEST(CheckTensors, HalfTypesAreCheckedForNonFinite) {
  const std::uint16_t half[3] = {0x3C00, 0x7BFF, 0x7C00};   // 1, 65504, Inf
  const std::uint16_t bf[3] = {0x3F80, 0x7F7F, 0xFFC0};     // 1, max, NaN
  Writer w;
  w.add("h", weights::DType::F16, {3}, half);
  w.add("b", weights::DType::BF16, {3}, bf);
  SafeTensors st = SafeTensors::from_bytes(w.bytes(), "w.safetensors");
  EXPECT_EQ(check_error(st, {{"h", {3}}}), "w.safetensors: tensor 'h' contains Inf (element 2)");
  EXPECT_EQ(check_error(st, {{"b", {3}}}), "w.safetensors: tensor 'b' contains NaN (element 2)");
}

TEST(CheckTensors, IntegerTensorIsNotAWeight) {
  const std::int64_t idx[2] = {1, 2};
  Writer w;
  w.add_i64("index", {2}, idx);
  SafeTensors st = SafeTensors::from_bytes(w.bytes(), "w.safetensors");
  EXPECT_EQ(check_error(st, {{"index", {2}}}),
            "w.safetensors: tensor 'index' has dtype I64, expected a float type (F32, F16 or BF16)");
}

TEST(CheckTensors, FirstProblemInSpecOrderWins) {
  SafeTensors st = convnext_like(std::numeric_limits<float>::quiet_NaN(), 1);
  std::string msg = check_error(st, {{"features.1.0.block.0.weight", {1}}, {"features.0.0.bias", {96}}});
  EXPECT_NE(msg.find("'features.1.0.block.0.weight' has shape"), std::string::npos) << msg;
}

TEST(CheckTensors, UnusedTensorsAreListedInFileOrder) {
  SafeTensors st = convnext_like();
  std::vector<std::string> unused = weights::check_tensors(st, {{"features.0.0.bias", {96}}});
  EXPECT_EQ(unused, (std::vector<std::string>{"features.0.0.weight", "features.1.0.block.0.weight"}));
}

TEST(CheckTensors, PaddingIsNeverReportedUnused) {
  SafeTensors st = SafeTensors::from_bytes(
      weights_test::file_bytes(
          R"({"w":{"dtype":"F32","shape":[1],"data_offsets":[0,4]},)"
          R"("__pad__1":{"dtype":"U8","shape":[60],"data_offsets":[4,64]},)"
          R"("extra":{"dtype":"F32","shape":[1],"data_offsets":[64,68]}})",
          68),
      "w.safetensors");
  EXPECT_EQ(weights::check_tensors(st, {{"w", {1}}}), std::vector<std::string>{"extra"});
}

}  // namespace
