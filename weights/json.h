// A strict, bounded JSON parser (RFC 8259) for files that come from outside:
// safetensors headers, calibration files, labelme annotations. Rejects duplicate
// object keys, nesting deeper than 64, invalid UTF-8 escapes, trailing garbage.
// Errors name the source and the position: "calib.json: line 3, column 7: expected ','"
// (lines count '\n', columns count characters, both from 1). Also rejected: control
// characters in strings, invalid UTF-8 anywhere, unpaired \u surrogates, leading
// zeros, a byte order mark, and numbers beyond the double range (those below it
// parse as zero). \u0000 is accepted and yields a NUL byte in the std::string.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace json {

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& what) : std::runtime_error(what) {}
};

class Value {
 public:
  enum class Type { Null, Bool, Number, String, Array, Object };

  Type type() const { return type_; }
  bool is_null() const { return type_ == Type::Null; }
  bool is_bool() const { return type_ == Type::Bool; }
  bool is_number() const { return type_ == Type::Number; }
  bool is_string() const { return type_ == Type::String; }
  bool is_array() const { return type_ == Type::Array; }
  bool is_object() const { return type_ == Type::Object; }

  // Accessors throw json::Error if the type does not match.
  bool boolean() const;
  double number() const;
  // The number exactly as written (for integers beyond 2^53).
  const std::string& number_text() const;
  // True and *out set if the number is a plain non-negative integer (no sign,
  // fraction or exponent) that fits in uint64.
  bool as_u64(std::uint64_t* out) const;
  const std::string& str() const;
  const std::vector<Value>& array() const;
  // Members in file order; keys are unique.
  const std::vector<std::pair<std::string, Value>>& object() const;
  // Object member or nullptr.
  const Value* get(std::string_view key) const;

  static Value make_null();
  static Value make_bool(bool b);
  static Value make_number(std::string text, double v);
  static Value make_string(std::string s);
  static Value make_array(std::vector<Value> items);
  static Value make_object(std::vector<std::pair<std::string, Value>> members);

  Value() noexcept : type_(Type::Null) {}
  Value(const Value& other);
  Value(Value&& other) noexcept;
  Value& operator=(const Value& other);
  Value& operator=(Value&& other) noexcept;
  ~Value();

 private:
  void destroy() noexcept;
  void construct_from(const Value& other);
  void construct_from(Value&& other) noexcept;

  // Only the member for type_ is alive (text_ for strings and numbers), which
  // keeps a Value at 48 bytes: parsed trees of multi-MB files stay small.
  Type type_;
  bool b_ = false;
  double num_ = 0;
  union {
    std::string text_;  // string value, or number text
    std::vector<Value> items_;
    std::vector<std::pair<std::string, Value>> members_;
  };
};

// Parses a whole document; `source` names it in error messages. Cost is linear;
// a parsed Value takes 48 bytes plus its strings and containers.
Value parse(std::string_view text, const std::string& source);

// Reads and parses a file (size limit 64 MiB); errors name the path.
Value parse_file(const std::string& path);

// A JSON string literal (with quotes) for writers: escapes '"', '\\' and control
// characters, passes other UTF-8 through. Throws json::Error if `s` is not valid
// UTF-8 (JSON text cannot carry it).
std::string quote(std::string_view s);

}  // namespace json
