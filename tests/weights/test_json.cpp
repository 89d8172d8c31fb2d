// The strict JSON parser: what it accepts, every rejection, and where errors point.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "weights/json.h"

namespace {

// Parses text that must fail and returns the message.
std::string parse_error(const std::string& text) {
  try {
    json::parse(text, "doc.json");
  } catch (const json::Error& e) {
    return e.what();
  }
  ADD_FAILURE() << "accepted: " << text;
  return "";
}

void expect_error(const std::string& text, const std::string& position, const std::string& problem) {
  std::string msg = parse_error(text);
  EXPECT_NE(msg.find("doc.json: " + position + ": "), std::string::npos) << msg;
  EXPECT_NE(msg.find(problem), std::string::npos) << msg;
  EXPECT_EQ(msg.find('\n'), std::string::npos) << "message spans lines: " << msg;
}

TEST(Json, ParsesScalars) {
  EXPECT_TRUE(json::parse("null", "t").is_null());
  EXPECT_TRUE(json::parse("true", "t").boolean());
  EXPECT_FALSE(json::parse(" false ", "t").boolean());
  EXPECT_EQ(json::parse("\"hi\"", "t").str(), "hi");
  EXPECT_EQ(json::parse("-12.5e1", "t").number(), -125.0);
  EXPECT_EQ(json::parse("0", "t").number(), 0.0);
  EXPECT_TRUE(std::signbit(json::parse("-0", "t").number()));
  EXPECT_EQ(json::parse("1E+2", "t").number(), 100.0);
  EXPECT_EQ(json::parse("0.1", "t").number(), 0.1);
  EXPECT_EQ(json::parse("5e-1", "t").number(), 0.5);
}

TEST(Json, ParsesNestedDocument) {
  json::Value v = json::parse(
      "{\"name\": \"cam\", \"k\": [[1, 0, 2], [0, 1, 3]], \"on\": true, \"x\": null, \"o\": {}}\n",
      "t");
  ASSERT_TRUE(v.is_object());
  ASSERT_EQ(v.object().size(), 5u);
  EXPECT_EQ(v.object()[0].first, "name");
  EXPECT_EQ(v.object()[4].first, "o");
  EXPECT_EQ(v.get("name")->str(), "cam");
  EXPECT_EQ(v.get("k")->array()[1].array()[2].number(), 3.0);
  EXPECT_TRUE(v.get("on")->boolean());
  EXPECT_TRUE(v.get("x")->is_null());
  EXPECT_TRUE(v.get("o")->object().empty());
  EXPECT_EQ(v.get("missing"), nullptr);
  EXPECT_TRUE(json::parse("[]", "t").array().empty());
}

TEST(Json, NumbersKeepTheirText) {
  json::Value big = json::parse("18446744073709551615", "t");
  EXPECT_EQ(big.number_text(), "18446744073709551615");
  std::uint64_t u = 0;
  ASSERT_TRUE(big.as_u64(&u));
  EXPECT_EQ(u, 18446744073709551615ull);
  EXPECT_EQ(json::parse("1.50", "t").number_text(), "1.50");
}

TEST(Json, AsU64RejectsWhatIsNotAPlainUnsignedInteger) {
  std::uint64_t u = 7;
  EXPECT_FALSE(json::parse("18446744073709551616", "t").as_u64(&u));  // 2^64
  EXPECT_FALSE(json::parse("-1", "t").as_u64(&u));
  EXPECT_FALSE(json::parse("-0", "t").as_u64(&u));
  EXPECT_FALSE(json::parse("2.0", "t").as_u64(&u));
  EXPECT_FALSE(json::parse("2e3", "t").as_u64(&u));
  EXPECT_FALSE(json::parse("\"5\"", "t").as_u64(&u));
  EXPECT_EQ(u, 7u);
  EXPECT_TRUE(json::parse("0", "t").as_u64(&u));
  EXPECT_EQ(u, 0u);
  EXPECT_FALSE(json::Value::make_number("007", 7).as_u64(&u));
}

TEST(Json, HugeAndTinyNumbers) {
  expect_error("[1e400]", "line 1, column 2", "too large");
  expect_error("-2e99999999999999999999", "line 1, column 1", "too large");
  EXPECT_EQ(json::parse("1e-400", "t").number(), 0.0);
  EXPECT_TRUE(std::signbit(json::parse("-1e-400", "t").number()));
  EXPECT_EQ(json::parse("0.0000000000000000000000000000000000000000000001e-300", "t").number(), 0.0);
  EXPECT_EQ(json::parse("123456789012345678901234567890", "t").number(),
            123456789012345678901234567890.0);
}

TEST(Json, StringEscapes) {
  EXPECT_EQ(json::parse(R"("a\"b\\c\/d\be\ff\ng\rh\ti")", "t").str(), "a\"b\\c/d\be\ff\ng\rh\ti");
  EXPECT_EQ(json::parse(R"("\u0041\u00e9\u20AC")", "t").str(), "A\xC3\xA9\xE2\x82\xAC");
  // U+1F600 as a surrogate pair becomes one 4-byte UTF-8 sequence.
  EXPECT_EQ(json::parse(R"("\uD83D\uDE00")", "t").str(), "\xF0\x9F\x98\x80");
  std::string nul = json::parse(R"("a\u0000b")", "t").str();
  EXPECT_EQ(nul, std::string("a\0b", 3));
  EXPECT_EQ(json::parse("\"h\xC3\xA9llo \xF0\x9F\x98\x80\"", "t").str(), "h\xC3\xA9llo \xF0\x9F\x98\x80");
}

TEST(Json, RejectsDuplicateKeys) {
  expect_error(R"({"a": 1, "b": 2, "a": 3})", "line 1, column 18", "duplicate key \"a\"");
  // Large objects use a hash set: same answer.
  std::string big = "{";
  for (int i = 0; i < 100; ++i) big += "\"k" + std::to_string(i) + "\": " + std::to_string(i) + ", ";
  std::string ok = big + "\"last\": 0}";
  EXPECT_EQ(json::parse(ok, "t").object().size(), 101u);
  std::string dup = big + "\"k42\": 0}";
  EXPECT_NE(parse_error(dup).find("duplicate key \"k42\""), std::string::npos);
  // Same key in different objects is fine.
  EXPECT_NO_THROW(json::parse(R"([{"a": 1}, {"a": 2}, {"x": {"a": 3}}])", "t"));
}

TEST(Json, DepthLimitIs64) {
  std::string ok = std::string(64, '[') + std::string(64, ']');
  EXPECT_NO_THROW(json::parse(ok, "t"));
  std::string deep = std::string(65, '[') + std::string(65, ']');
  expect_error(deep, "line 1, column 65", "nesting deeper than 64");
  std::string objects;
  for (int i = 0; i < 65; ++i) objects += "{\"a\":";
  objects += "1" + std::string(65, '}');
  EXPECT_NE(parse_error(objects).find("nesting deeper than 64"), std::string::npos);
  // Far deeper input must fail cleanly, not overflow the stack.
  EXPECT_NE(parse_error(std::string(100000, '[')).find("nesting"), std::string::npos);
}

TEST(Json, RejectsBadEscapes) {
  expect_error(R"("ab\x")", "line 1, column 4", "invalid escape '\\x'");
  expect_error(R"("\u12G4")", "line 1, column 2", "expected 4 hex digits");
  expect_error(R"("\u12")", "line 1, column 2", "expected 4 hex digits");
  expect_error(R"("\uD800")", "line 1, column 2", "unpaired high surrogate");
  expect_error(R"("\uD800x")", "line 1, column 2", "unpaired high surrogate");
  expect_error(R"("\uDC00")", "line 1, column 2", "unpaired low surrogate");
  expect_error(R"("\uD800\u0041")", "line 1, column 8", "expected a low surrogate");
  expect_error("\"\\\x01\"", "line 1, column 2", "invalid escape byte 0x01");
}

TEST(Json, RejectsControlCharactersInStrings) {
  expect_error("\"a\nb\"", "line 1, column 3", "control character 0x0A");
  expect_error(std::string("\"a\0b\"", 5), "line 1, column 3", "control character 0x00");
  expect_error("\"tab\there\"", "line 1, column 5", "control character 0x09");
}

TEST(Json, RejectsInvalidUtf8) {
  expect_error("\"\xFF\"", "line 1, column 2", "invalid UTF-8 byte 0xFF");
  expect_error("\"\xC0\xAF\"", "line 1, column 2", "invalid UTF-8");        // overlong '/'
  expect_error("\"\xE0\x80\xAF\"", "line 1, column 2", "invalid UTF-8");    // overlong 3-byte
  expect_error("\"\xED\xA0\x80\"", "line 1, column 2", "invalid UTF-8");    // encoded surrogate
  expect_error("\"\xF4\x90\x80\x80\"", "line 1, column 2", "invalid UTF-8");  // > U+10FFFF
  expect_error("\"\xC3\"", "line 1, column 2", "invalid UTF-8");            // cut short
  expect_error("\"\x80\"", "line 1, column 2", "invalid UTF-8");            // lone continuation
  expect_error("[\xFF]", "line 1, column 2", "invalid UTF-8 byte 0xFF");    // outside strings
  expect_error("[\xC3\xA9]", "line 1, column 2", "expected a JSON value, found '\xC3\xA9'");
}

TEST(Json, RejectsTrailingData) {
  expect_error("{} x", "line 1, column 4", "trailing data");
  expect_error("1 2", "line 1, column 3", "trailing data");
  expect_error("[1]]", "line 1, column 4", "trailing data");
  expect_error("\"a\"\"b\"", "line 1, column 4", "trailing data");
}

TEST(Json, RejectsMalformedNumbers) {
  expect_error("01", "line 1, column 1", "leading zero");
  expect_error("[-007]", "line 1, column 2", "leading zero");
  expect_error("-", "line 1, column 2", "expected a digit after '-'");
  expect_error("1.", "line 1, column 3", "expected a digit after '.'");
  expect_error("1.e5", "line 1, column 3", "expected a digit after '.'");
  expect_error("1e", "line 1, column 3", "expected a digit in the exponent");
  expect_error("1e+", "line 1, column 4", "expected a digit in the exponent");
  expect_error("+1", "line 1, column 1", "expected a JSON value, found '+'");
  expect_error(".5", "line 1, column 1", "expected a JSON value, found '.'");
  expect_error("NaN", "line 1, column 1", "expected a JSON value");
  expect_error("[Infinity]", "line 1, column 2", "expected a JSON value");
  expect_error("0x10", "line 1, column 2", "trailing data");
}

TEST(Json, RejectsTruncatedDocuments) {
  expect_error("", "line 1, column 1", "empty input");
  expect_error("  \n ", "line 2, column 2", "empty input");
  expect_error("{", "line 1, column 2", "unexpected end of input");
  expect_error("{\"a\"", "line 1, column 5", "expected ':'");
  expect_error("{\"a\":", "line 1, column 6", "unexpected end of input");
  expect_error("{\"a\":1", "line 1, column 7", "expected ',' or '}'");
  expect_error("[1,", "line 1, column 4", "unexpected end of input");
  expect_error("[1", "line 1, column 3", "expected ',' or ']'");
  expect_error("\"abc", "line 1, column 1", "unterminated string");
  expect_error("\"abc\\", "line 1, column 1", "unterminated string");
  expect_error("tru", "line 1, column 1", "expected 'true'");
  expect_error("nul", "line 1, column 1", "expected 'null'");
}

TEST(Json, RejectsStructuralMistakes) {
  expect_error("[1,]", "line 1, column 4", "trailing comma");
  expect_error("{\"a\":1,}", "line 1, column 8", "trailing comma");
  expect_error("{a:1}", "line 1, column 2", "expected a string key, found 'a'");
  expect_error("{\"a\" 1}", "line 1, column 6", "expected ':' after object key, found '1'");
  expect_error("[1 2]", "line 1, column 4", "expected ',' or ']' in array, found '2'");
  expect_error("{\"a\":1 \"b\":2}", "line 1, column 8", "expected ',' or '}' in object");
  expect_error("[True]", "line 1, column 2", "expected a JSON value, found 'T'");
  expect_error("// c\n{}", "line 1, column 1", "found '/'");
  expect_error("\xEF\xBB\xBF{}", "line 1, column 1", "byte order mark");
}

TEST(Json, ErrorPositionsCountLinesAndCharacters) {
  // Column counts characters, not bytes: the two-byte e-acute is one column.
  expect_error("{\n  \"caf\xC3\xA9\": 1,\n  \"b\": [1, 2,, 3]\n}", "line 3, column 14",
               "expected a JSON value, found ','");
  expect_error("{\"caf\xC3\xA9\": [1,, 2]}", "line 1, column 13", "found ','");
  expect_error("\r\n\r\n   x", "line 3, column 4", "found 'x'");
}

TEST(Json, AccessorsCheckTheType) {
  json::Value v = json::parse("[1]", "t");
  EXPECT_THROW(v.str(), json::Error);
  EXPECT_THROW(v.object(), json::Error);
  EXPECT_THROW(v.get("a"), json::Error);
  EXPECT_THROW(v.array()[0].boolean(), json::Error);
  EXPECT_THROW(v.array()[0].str(), json::Error);
  EXPECT_THROW(json::parse("\"x\"", "t").number(), json::Error);
  EXPECT_THROW(json::parse("\"x\"", "t").number_text(), json::Error);
  std::uint64_t u;
  EXPECT_FALSE(v.as_u64(&u));
}

TEST(Json, QuoteRoundTrips) {
  std::string nasty = std::string("a\"b\\c\n\t\x01\x1f/\xC3\xA9\xF0\x9F\x98\x80", 16);
  nasty += '\0';
  std::string q = json::quote(nasty);
  EXPECT_EQ(q.find('\n'), std::string::npos);
  EXPECT_EQ(json::parse(q, "t").str(), nasty);
  EXPECT_EQ(json::quote("x"), "\"x\"");
  EXPECT_EQ(json::quote(std::string("\x01", 1)), "\"\\u0001\"");
  EXPECT_THROW(json::quote("bad \xFF byte"), json::Error);
}

TEST(Json, LargeDocumentParses) {
  // A labelme-sized file: many small objects and a long base64-like string.
  std::string doc = "{\"imageData\": \"" + std::string(3 << 20, 'A') + "\", \"shapes\": [";
  for (int i = 0; i < 20000; ++i) {
    if (i) doc += ",";
    doc += "{\"label\": \"car\", \"points\": [[" + std::to_string(i) + ".5, 2], [3, 4.25]]}";
  }
  doc += "]}";
  json::Value v = json::parse(doc, "big.json");
  EXPECT_EQ(v.get("imageData")->str().size(), 3u << 20);
  const auto& shapes = v.get("shapes")->array();
  ASSERT_EQ(shapes.size(), 20000u);
  EXPECT_EQ(shapes[19999].get("points")->array()[0].array()[0].number(), 19999.5);
}

}  // namespace

namespace {

TEST(JsonValue, CopiesAreDeepAndAssignmentHandlesAliasing) {
  json::Value v = json::parse(R"([{"k": ["deep", 1.5]}, "two", 3, true, null])", "t");
  json::Value copy = v;
  json::Value moved = json::Value(copy);
  // Assigning a value from inside itself must not read freed memory.
  v = v.array()[0];
  ASSERT_TRUE(v.is_object());
  EXPECT_EQ(v.get("k")->array()[0].str(), "deep");
  json::Value inner = v;
  inner = inner.object()[0].second;  // assign from a member of itself
  ASSERT_TRUE(inner.is_array());
  EXPECT_EQ(inner.array()[1].number_text(), "1.5");
  const json::Value& self = copy;
  copy = self;
  ASSERT_EQ(copy.array().size(), 5u);
  EXPECT_EQ(copy.array()[1].str(), "two");
  EXPECT_EQ(moved.array()[2].number(), 3.0);
  EXPECT_TRUE(moved.array()[3].boolean());
  EXPECT_TRUE(moved.array()[4].is_null());
  // Changing type by assignment releases the old payload and takes the new one.
  json::Value x = json::Value::make_string(std::string(1000, 'x'));
  x = json::Value::make_number("7", 7);
  EXPECT_EQ(x.number(), 7.0);
  x = json::Value::make_bool(false);
  EXPECT_FALSE(x.boolean());
  EXPECT_THROW(x.number_text(), json::Error);
}

}  // namespace

namespace {

TEST(JsonValue, StaysCompact) {
  // Trees of multi-MB labelme files are dominated by Value nodes.
  EXPECT_LE(sizeof(json::Value), 48u);
}

}  // namespace

// Found by tests/fuzz/fuzz_smartereye: JSON strings may hold a raw DEL (0x7F), and a
// duplicate key holding one went into the message unescaped.
TEST(Json, DuplicateKeyWithDelIsEscapedInTheMessage) {
  std::string m = parse_error("{\"p\x7fq\": 1, \"p\x7fq\": 2}");
  EXPECT_NE(m.find("duplicate key \"p\\u007fq\""), std::string::npos) << m;
  for (unsigned char c : m) EXPECT_TRUE(c >= 0x20 && c != 0x7f) << m;
}
