// Every malformed safetensors case gets its own test and a precise message that
// names the file and the problem.
#include <gtest/gtest.h>

#include <string>

#include "tests/weights/safetensors_bytes.h"
#include "weights/safetensors.h"

namespace {

using weights_test::file_bytes;
using weights_test::load_error;

void expect_problem(const std::vector<std::uint8_t>& bytes, const std::string& problem) {
  std::string msg = load_error(bytes);
  ASSERT_FALSE(msg.empty()) << "accepted, expected: " << problem;
  EXPECT_EQ(msg.rfind("w.safetensors: ", 0), 0u) << msg;
  EXPECT_NE(msg.find(problem), std::string::npos) << msg;
  EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
}

// One tensor entry in a header.
std::string entry(const std::string& name, const std::string& dtype, const std::string& shape,
                  const std::string& offsets) {
  return "\"" + name + "\":{\"dtype\":\"" + dtype + "\",\"shape\":" + shape +
         ",\"data_offsets\":" + offsets + "}";
}

TEST(SafeTensorsMalformed, ValidBaselineIsAccepted) {
  // The fixtures below are this file with one thing broken.
  EXPECT_EQ(load_error(file_bytes("{" + entry("a", "F32", "[2]", "[0,8]") + "}", 8)), "");
  EXPECT_EQ(load_error(file_bytes("{}", 0)), "");
  EXPECT_EQ(load_error(file_bytes("  {}    ", 0)), "");
}

TEST(SafeTensorsMalformed, FileShorterThanEightBytes) {
  expect_problem({}, "file is 0 bytes, too short for the 8-byte header length");
  expect_problem({1, 0, 0}, "file is 3 bytes, too short");
}

TEST(SafeTensorsMalformed, HeaderLengthPastTheEnd) {
  expect_problem(file_bytes("{}", 0, 1000), "header length 1000 runs past the end of the file (size 10)");
  expect_problem(file_bytes("{}", 0, 3), "header length 3 runs past the end of the file (size 10)");
}

TEST(SafeTensorsMalformed, HeaderLengthAboveLimit) {
  expect_problem(file_bytes("{}", 0, 100000001), "header length 100000001 exceeds the limit");
  // Lengths where 8 + N would wrap around must not sneak through.
  expect_problem(file_bytes("{}", 0, ~0ull), "exceeds the limit");
  expect_problem(file_bytes("{}", 0, ~0ull - 7), "exceeds the limit");
}

TEST(SafeTensorsMalformed, InvalidJson) {
  expect_problem(file_bytes("{\"a\": ", 0), "w.safetensors: header: line 1, column 7: unexpected end of input");
  expect_problem(file_bytes("{\"a\":1}x", 0), "trailing data");
  expect_problem(file_bytes("{\"\xFF\":1}", 0), "invalid UTF-8");
}

TEST(SafeTensorsMalformed, HeaderNotAnObject) {
  expect_problem(file_bytes("[]", 0), "header is an array, expected a JSON object");
}

TEST(SafeTensorsMalformed, DuplicateKey) {
  expect_problem(file_bytes("{" + entry("a", "U8", "[1]", "[0,1]") + "," +
                                entry("a", "U8", "[1]", "[1,2]") + "}",
                            2),
                 "duplicate key \"a\"");
}

TEST(SafeTensorsMalformed, UnknownDtype) {
  expect_problem(file_bytes("{" + entry("a", "X9", "[1]", "[0,1]") + "}", 1),
                 "tensor 'a': unknown dtype 'X9'");
  expect_problem(file_bytes("{\"a\":{\"dtype\":5,\"shape\":[1],\"data_offsets\":[0,1]}}", 1),
                 "tensor 'a': dtype is 5, expected a string");
}

TEST(SafeTensorsMalformed, OverlappingOffsets) {
  expect_problem(file_bytes("{" + entry("a", "F32", "[2]", "[0,8]") + "," +
                                entry("b", "F32", "[2]", "[4,12]") + "}",
                            12),
                 "overlap: tensor 'b' (begins at 4) overlaps tensor 'a' (ends at 8)");
  // Two tensors sharing the same bytes.
  expect_problem(file_bytes("{" + entry("a", "F32", "[1]", "[0,4]") + "," +
                                entry("b", "F32", "[1]", "[0,4]") + "}",
                            4),
                 "overlap");
}

TEST(SafeTensorsMalformed, GappedOffsets) {
  expect_problem(file_bytes("{" + entry("a", "F32", "[1]", "[0,4]") + "," +
                                entry("b", "F32", "[1]", "[8,12]") + "}",
                            12),
                 "gap of 4 bytes between tensor 'a' (ends at 4) and tensor 'b' (begins at 8)");
  expect_problem(file_bytes("{" + entry("a", "F32", "[1]", "[4,8]") + "}", 8),
                 "gap of 4 bytes at the start of the data, before tensor 'a'");
}

TEST(SafeTensorsMalformed, TrailingBytes) {
  expect_problem(file_bytes("{" + entry("a", "F32", "[1]", "[0,4]") + "}", 6),
                 "2 trailing bytes after the last tensor");
  expect_problem(file_bytes("{}", 3), "3 trailing bytes after the last tensor");
}

TEST(SafeTensorsMalformed, DataCutShort) {
  expect_problem(file_bytes("{" + entry("a", "F32", "[2]", "[0,8]") + "}", 5),
                 "data truncated: tensor 'a' ends at byte 8 of the data, but only 5 data bytes follow");
  // A real file losing its last byte.
  const float v[4] = {1, 2, 3, 4};
  weights::Writer w;
  w.add_f32("last", {4}, v);
  std::vector<std::uint8_t> bytes = w.bytes();
  bytes.pop_back();
  expect_problem(bytes, "data truncated: tensor 'last'");
}

TEST(SafeTensorsMalformed, WrongByteCountForShape) {
  expect_problem(file_bytes("{" + entry("a", "F32", "[3]", "[0,8]") + "}", 8),
                 "tensor 'a': data_offsets [0, 8] hold 8 bytes, but shape [3] of F32 needs 12");
  expect_problem(file_bytes("{" + entry("a", "F16", "[2,2]", "[0,16]") + "}", 16),
                 "shape [2, 2] of F16 needs 8");
}

TEST(SafeTensorsMalformed, ShapeOverflow) {
  expect_problem(file_bytes("{" + entry("a", "F32", "[1099511627776,1099511627776,1099511627776]",
                                        "[0,4]") + "}",
                            4),
                 "tensor 'a': shape [1099511627776, 1099511627776, 1099511627776] is too large");
  // The element count fits in 63 bits, the byte count does not.
  expect_problem(file_bytes("{" + entry("a", "F32", "[4611686018427387904]", "[0,0]") + "}", 0),
                 "is too large");
  expect_problem(file_bytes("{" + entry("a", "U8", "[9223372036854775808]", "[0,0]") + "}", 0),
                 "shape dimension 0 is 9223372036854775808, expected a non-negative integer");
}

TEST(SafeTensorsMalformed, ZeroDimensionMakesHugeShapesEmpty) {
  // [2^40, 2^40, 0] has no elements: valid, not an overflow.
  EXPECT_EQ(load_error(file_bytes(
                "{" + entry("a", "F32", "[1099511627776,1099511627776,0]", "[0,0]") + "}", 0)),
            "");
}

TEST(SafeTensorsMalformed, RankNine) {
  expect_problem(file_bytes("{" + entry("a", "U8", "[1,1,1,1,1,1,1,1,1]", "[0,1]") + "}", 1),
                 "tensor 'a': rank 9 exceeds the maximum of 8");
  EXPECT_EQ(load_error(file_bytes("{" + entry("a", "U8", "[1,1,1,1,1,1,1,1]", "[0,1]") + "}", 1)), "");
}

TEST(SafeTensorsMalformed, NegativeDimension) {
  expect_problem(file_bytes("{" + entry("a", "F32", "[2,-3]", "[0,0]") + "}", 0),
                 "tensor 'a': shape dimension 1 is -3, expected a non-negative integer");
}

TEST(SafeTensorsMalformed, FractionalDimension) {
  expect_problem(file_bytes("{" + entry("a", "F32", "[2.5]", "[0,8]") + "}", 8),
                 "shape dimension 0 is 2.5, expected a non-negative integer");
  expect_problem(file_bytes("{" + entry("a", "F32", "[2.0]", "[0,8]") + "}", 8),
                 "shape dimension 0 is 2.0");
  expect_problem(file_bytes("{" + entry("a", "F32", "[2e0]", "[0,8]") + "}", 8),
                 "shape dimension 0 is 2e0");
  expect_problem(file_bytes("{" + entry("a", "F32", "[\"2\"]", "[0,8]") + "}", 8),
                 "shape dimension 0 is a string");
  expect_problem(file_bytes("{\"a\":{\"dtype\":\"F32\",\"shape\":2,\"data_offsets\":[0,8]}}", 8),
                 "tensor 'a': shape is 2, expected an array");
}

TEST(SafeTensorsMalformed, BadDataOffsets) {
  const std::string why = "data_offsets must be an array of two non-negative integers";
  expect_problem(file_bytes("{" + entry("a", "U8", "[1]", "[0,1,2]") + "}", 2), why);
  expect_problem(file_bytes("{" + entry("a", "U8", "[1]", "[-1,0]") + "}", 1), why);
  expect_problem(file_bytes("{" + entry("a", "U8", "[1]", "[0.0,1]") + "}", 1), why);
  expect_problem(file_bytes("{" + entry("a", "U8", "[1]", "{}") + "}", 1), why);
  expect_problem(file_bytes("{" + entry("a", "U8", "[1]", "[5,4]") + "}", 5),
                 "data_offsets [5, 4] end before they begin");
  // Offsets far beyond the file fail the layout check; they are never dereferenced.
  expect_problem(file_bytes("{" + entry("a", "U8", "[1]", "[18446744073709551614,18446744073709551615]") +
                                "}",
                            1),
                 "gap of 18446744073709551614 bytes at the start");
}

TEST(SafeTensorsMalformed, MetadataWithNonStringValue) {
  expect_problem(file_bytes("{\"__metadata__\":{\"k\":1}}", 0),
                 "__metadata__ value for key 'k' is 1, expected a string");
  expect_problem(file_bytes("{\"__metadata__\":{\"k\":null}}", 0), "is null, expected a string");
  expect_problem(file_bytes("{\"__metadata__\":[\"k\"]}", 0), "__metadata__ is an array, expected an object");
}

TEST(SafeTensorsMalformed, EntryFields) {
  expect_problem(file_bytes("{\"a\":[1]}", 0), "tensor 'a': entry is an array, expected an object");
  expect_problem(file_bytes("{\"a\":{\"dtype\":\"U8\",\"shape\":[0]}}", 0),
                 "tensor 'a': missing field 'data_offsets'");
  expect_problem(file_bytes("{\"a\":{\"shape\":[0],\"data_offsets\":[0,0]}}", 0),
                 "tensor 'a': missing field 'dtype'");
  expect_problem(file_bytes("{\"a\":{\"dtype\":\"U8\",\"shape\":[0],\"data_offsets\":[0,0],\"x\":1}}", 0),
                 "tensor 'a': unexpected field 'x'");
}

TEST(SafeTensorsMalformed, ControlCharactersInNamesStayOnOneLine) {
  expect_problem(file_bytes("{" + entry("a\\nb", "X9", "[1]", "[0,1]") + "}", 1),
                 "tensor 'a\\x0ab': unknown dtype");
}

TEST(SafeTensorsPadding, PaddingTensorsAreValidatedButHidden) {
  weights::SafeTensors st = weights::SafeTensors::from_bytes(
      file_bytes("{" + entry("a", "U8", "[3]", "[0,3]") + "," +
                     entry("__pad__0", "U8", "[5]", "[3,8]") + "," +
                     entry("b", "F32", "[1]", "[8,12]") + "}",
                 12),
      "mem");
  EXPECT_EQ(st.names(), (std::vector<std::string>{"a", "b"}));
  EXPECT_FALSE(st.has("__pad__0"));
  EXPECT_THROW(st.info("__pad__0"), weights::Error);
  EXPECT_EQ(st.tensors().size(), 2u);
}

TEST(SafeTensorsPadding, PaddingMustBeU8) {
  expect_problem(file_bytes("{" + entry("__pad__0", "F32", "[1]", "[0,4]") + "}", 4),
                 "padding tensor '__pad__0' must be a rank-1 U8 tensor");
}

TEST(SafeTensorsMalformed, EmptyTensorsMayShareAnOffset) {
  weights::SafeTensors st = weights::SafeTensors::from_bytes(
      file_bytes("{" + entry("full", "U8", "[2]", "[0,2]") + "," + entry("e1", "F32", "[0]", "[0,0]") +
                     "," + entry("e2", "F32", "[0,3]", "[0,0]") + "," +
                     entry("tail", "U8", "[0]", "[2,2]") + "}",
                 2),
      "mem");
  EXPECT_EQ(st.names(), (std::vector<std::string>{"e1", "e2", "full", "tail"}));
}

}  // namespace
