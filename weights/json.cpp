// Strict RFC 8259 parser. Positions are reported as line and column (in
// characters) computed only when an error is raised, so the happy path costs
// nothing for them.
#include "weights/json.h"

#include <algorithm>
#include <charconv>
#include <cstring>
#include <functional>
#include <iterator>
#include <new>
#include <unordered_set>

#include "weights/file_io.h"

namespace json {
namespace {

constexpr int kMaxDepth = 64;
constexpr std::uint64_t kMaxFileBytes = 64ull << 20;
// Objects up to this size are checked for duplicate keys by a linear scan; larger
// ones switch to a hash set (safetensors headers have hundreds of keys).
constexpr std::size_t kLinearKeyCheck = 16;

const char* type_name(Value::Type t) {
  switch (t) {
    case Value::Type::Null: return "null";
    case Value::Type::Bool: return "a boolean";
    case Value::Type::Number: return "a number";
    case Value::Type::String: return "a string";
    case Value::Type::Array: return "an array";
    case Value::Type::Object: return "an object";
  }
  return "?";
}

[[noreturn]] void wrong_type(Value::Type have, Value::Type want) {
  throw Error(std::string("JSON value is ") + type_name(have) + ", expected " + type_name(want));
}

bool is_digit(char c) { return c >= '0' && c <= '9'; }
bool is_continuation(unsigned char c) { return (c & 0xC0) == 0x80; }

// Length of the valid UTF-8 sequence starting at p (lead byte >= 0x80), or 0 if
// it is malformed: overlong forms, encoded surrogates, code points above U+10FFFF
// and sequences cut off by `end` are all rejected.
std::size_t utf8_sequence_length(const unsigned char* p, const unsigned char* end) {
  unsigned char c = p[0];
  std::size_t avail = static_cast<std::size_t>(end - p);
  unsigned char lo = 0x80, hi = 0xBF;
  std::size_t len;
  if (c >= 0xC2 && c <= 0xDF) {
    len = 2;
  } else if (c >= 0xE0 && c <= 0xEF) {
    len = 3;
    if (c == 0xE0) lo = 0xA0;   // overlong below U+0800
    if (c == 0xED) hi = 0x9F;   // UTF-16 surrogates
  } else if (c >= 0xF0 && c <= 0xF4) {
    len = 4;
    if (c == 0xF0) lo = 0x90;   // overlong below U+10000
    if (c == 0xF4) hi = 0x8F;   // above U+10FFFF
  } else {
    return 0;
  }
  if (avail < len) return 0;
  if (p[1] < lo || p[1] > hi) return 0;
  for (std::size_t i = 2; i < len; ++i) {
    if (!is_continuation(p[i])) return 0;
  }
  return len;
}

void append_utf8(std::string& out, std::uint32_t cp) {
  if (cp < 0x80) {
    out += static_cast<char>(cp);
  } else if (cp < 0x800) {
    out += static_cast<char>(0xC0 | (cp >> 6));
    out += static_cast<char>(0x80 | (cp & 0x3F));
  } else if (cp < 0x10000) {
    out += static_cast<char>(0xE0 | (cp >> 12));
    out += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
    out += static_cast<char>(0x80 | (cp & 0x3F));
  } else {
    out += static_cast<char>(0xF0 | (cp >> 18));
    out += static_cast<char>(0x80 | ((cp >> 12) & 0x3F));
    out += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
    out += static_cast<char>(0x80 | (cp & 0x3F));
  }
}

std::string hex_byte(unsigned char c) {
  const char* digits = "0123456789ABCDEF";
  std::string s = "0x";
  s += digits[c >> 4];
  s += digits[c & 15];
  return s;
}

// How a character appears in a message: printable ASCII quoted, anything else as
// its byte value, so messages stay on one line.
std::string describe_char(unsigned char c) {
  if (c >= 0x20 && c < 0x7F) return std::string("'") + static_cast<char>(c) + "'";
  return "byte " + hex_byte(c);
}

// A key shortened for messages; quote() escapes control characters, so the
// message stays on one line.
// DEL (0x7F), which JSON strings may hold raw and quote() passes through, is written
// \u007f here (found by tests/fuzz/fuzz_smartereye: a duplicate key holding DEL).
std::string describe_key(const std::string& key) {
  constexpr std::size_t kMax = 80;
  std::size_t cut = key.size();
  if (cut > kMax) {
    cut = kMax;
    while (cut > 0 && is_continuation(static_cast<unsigned char>(key[cut]))) --cut;
  }
  std::string q = quote(key.substr(0, cut)), out;
  for (char ch : q) {
    if (ch == '\x7f')
      out += "\\u007f";
    else
      out += ch;
  }
  return cut < key.size() ? out + "..." : out;
}

class Parser {
 public:
  Parser(std::string_view text, const std::string& source)
      : begin_(text.data()), p_(text.data()), end_(text.data() + text.size()), source_(source) {}

  Value document() {
    if (end_ - p_ >= 3 && std::memcmp(p_, "\xEF\xBB\xBF", 3) == 0) {
      fail_at(p_, "byte order mark (U+FEFF) is not allowed");
    }
    skip_ws();
    if (p_ == end_) fail_at(p_, "empty input, expected a JSON value");
    Value v = value(0);
    skip_ws();
    if (p_ != end_) fail_at(p_, "trailing data after the JSON value: " + describe_here());
    return v;
  }

 private:
  [[noreturn]] void fail_at(const char* where, const std::string& problem) const {
    std::size_t line = 1, column = 1;
    for (const char* q = begin_; q < where; ++q) {
      unsigned char c = static_cast<unsigned char>(*q);
      if (c == '\n') {
        ++line;
        column = 1;
      } else if (!is_continuation(c)) {
        ++column;
      }
    }
    throw Error(source_ + ": line " + std::to_string(line) + ", column " + std::to_string(column) +
                ": " + problem);
  }

  std::string describe_here() const {
    if (p_ == end_) return "end of input";
    unsigned char c = static_cast<unsigned char>(*p_);
    if (c >= 0x80) {
      std::size_t len = utf8_sequence_length(reinterpret_cast<const unsigned char*>(p_),
                                             reinterpret_cast<const unsigned char*>(end_));
      if (len == 0) return "invalid UTF-8 byte " + hex_byte(c);
      return "'" + std::string(p_, len) + "'";
    }
    return describe_char(c);
  }

  void skip_ws() {
    while (p_ != end_ && (*p_ == ' ' || *p_ == '\n' || *p_ == '\t' || *p_ == '\r')) ++p_;
  }

  Value value(int depth) {
    if (p_ == end_) fail_at(p_, "unexpected end of input, expected a JSON value");
    switch (*p_) {
      case '{': return object(depth + 1);
      case '[': return array(depth + 1);
      case '"': return Value::make_string(string());
      case 't': literal("true"); return Value::make_bool(true);
      case 'f': literal("false"); return Value::make_bool(false);
      case 'n': literal("null"); return Value::make_null();
      default:
        if (*p_ == '-' || is_digit(*p_)) return number();
        fail_at(p_, "expected a JSON value, found " + describe_here());
    }
  }

  void literal(const char* word) {
    std::size_t n = std::strlen(word);
    if (static_cast<std::size_t>(end_ - p_) < n || std::memcmp(p_, word, n) != 0) {
      fail_at(p_, std::string("invalid literal, expected '") + word + "'");
    }
    p_ += n;
  }

  void enter(int depth) const {
    if (depth > kMaxDepth) {
      fail_at(p_, "nesting deeper than " + std::to_string(kMaxDepth) + " levels");
    }
  }

  // Containers are built on shared scratch stacks and moved into a vector of
  // the exact size when they close: one allocation per container instead of a
  // growth sequence, which dominates the cost of files with many small arrays.
  Value array(int depth) {
    enter(depth);
    ++p_;  // '['
    const std::size_t base = values_.size();
    skip_ws();
    if (p_ != end_ && *p_ == ']') {
      ++p_;
      return Value::make_array({});
    }
    for (;;) {
      skip_ws();
      if (p_ != end_ && *p_ == ']') fail_at(p_, "expected a JSON value, found ']' (trailing comma?)");
      Value item = value(depth);
      values_.push_back(std::move(item));
      skip_ws();
      if (p_ == end_) fail_at(p_, "unexpected end of input, expected ',' or ']' in array");
      if (*p_ == ',') {
        ++p_;
        continue;
      }
      if (*p_ == ']') {
        ++p_;
        std::vector<Value> items(std::make_move_iterator(values_.begin() + base),
                                 std::make_move_iterator(values_.end()));
        values_.erase(values_.begin() + base, values_.end());
        return Value::make_array(std::move(items));
      }
      fail_at(p_, "expected ',' or ']' in array, found " + describe_here());
    }
  }

  Value object(int depth) {
    enter(depth);
    ++p_;  // '{'
    const std::size_t base = members_.size();
    skip_ws();
    if (p_ != end_ && *p_ == '}') {
      ++p_;
      return Value::make_object({});
    }
    // Indices into members_, hashed by key: indices stay valid when the stack
    // reallocates, string views into short keys would not.
    auto hash = [this](std::size_t i) { return std::hash<std::string>()(members_[i].first); };
    auto equal = [this](std::size_t a, std::size_t b) {
      return members_[a].first == members_[b].first;
    };
    std::unordered_set<std::size_t, decltype(hash), decltype(equal)> seen(0, hash, equal);
    for (;;) {
      skip_ws();
      if (p_ == end_) fail_at(p_, "unexpected end of input, expected a string key");
      if (*p_ != '"') {
        if (*p_ == '}') fail_at(p_, "expected a string key, found '}' (trailing comma?)");
        fail_at(p_, "expected a string key, found " + describe_here());
      }
      const char* key_at = p_;
      std::string key = string();
      members_.emplace_back(std::move(key), Value());
      check_duplicate(base, seen, key_at);
      const std::size_t slot = members_.size() - 1;
      skip_ws();
      if (p_ == end_) fail_at(p_, "unexpected end of input, expected ':' after object key");
      if (*p_ != ':') fail_at(p_, "expected ':' after object key, found " + describe_here());
      ++p_;
      skip_ws();
      // value() may grow members_ (nested objects), so assign by index afterwards.
      Value v = value(depth);
      members_[slot].second = std::move(v);
      skip_ws();
      if (p_ == end_) fail_at(p_, "unexpected end of input, expected ',' or '}' in object");
      if (*p_ == ',') {
        ++p_;
        continue;
      }
      if (*p_ == '}') {
        ++p_;
        std::vector<std::pair<std::string, Value>> members(
            std::make_move_iterator(members_.begin() + base), std::make_move_iterator(members_.end()));
        members_.erase(members_.begin() + base, members_.end());
        return Value::make_object(std::move(members));
      }
      fail_at(p_, "expected ',' or '}' in object, found " + describe_here());
    }
  }

  // Checks the newest member of the object whose members start at `base`.
  template <class Set>
  void check_duplicate(std::size_t base, Set& seen, const char* key_at) const {
    const std::size_t last = members_.size() - 1;
    const std::string& key = members_[last].first;
    if (last - base < kLinearKeyCheck) {
      for (std::size_t i = base; i < last; ++i) {
        if (members_[i].first == key) fail_at(key_at, "duplicate key " + describe_key(key));
      }
      return;
    }
    if (seen.empty()) {
      for (std::size_t i = base; i < last; ++i) seen.insert(i);
    }
    if (!seen.insert(last).second) fail_at(key_at, "duplicate key " + describe_key(key));
  }

  static int hex_value(char c) {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
  }

  // Reads the 4 hex digits after "\u" at p_ (which points at the backslash).
  std::uint32_t unicode_escape() {
    const char* at = p_;
    if (end_ - p_ < 6) fail_at(at, "invalid \\u escape, expected 4 hex digits");
    std::uint32_t v = 0;
    for (int i = 2; i < 6; ++i) {
      int h = hex_value(p_[i]);
      if (h < 0) fail_at(at, "invalid \\u escape, expected 4 hex digits");
      v = v * 16 + static_cast<std::uint32_t>(h);
    }
    p_ += 6;
    return v;
  }

  std::string string() {
    const char* open = p_;
    ++p_;  // '"'
    std::string out;
    const char* run = p_;
    for (;;) {
      if (p_ == end_) fail_at(open, "unterminated string");
      unsigned char c = static_cast<unsigned char>(*p_);
      if (c == '"') {
        out.append(run, p_);
        ++p_;
        return out;
      }
      if (c == '\\') {
        out.append(run, p_);
        escape(out, open);
        run = p_;
        continue;
      }
      if (c < 0x20) {
        fail_at(p_, "control character " + hex_byte(c) + " in string (must be escaped)");
      }
      if (c < 0x80) {
        ++p_;
        skip_plain_ascii();
        continue;
      }
      std::size_t len = utf8_sequence_length(reinterpret_cast<const unsigned char*>(p_),
                                             reinterpret_cast<const unsigned char*>(end_));
      if (len == 0) fail_at(p_, "invalid UTF-8 byte " + hex_byte(c) + " in string");
      p_ += len;
    }
  }

  // Skips 8 bytes at a time while none of them needs attention in a string
  // (quote, backslash, control character, non-ASCII): base64 image data in
  // labelme files is megabytes of exactly that.
  void skip_plain_ascii() {
    constexpr std::uint64_t kOnes = 0x0101010101010101ull;
    constexpr std::uint64_t kHighs = 0x8080808080808080ull;
    while (end_ - p_ >= 8) {
      std::uint64_t x;
      std::memcpy(&x, p_, 8);
      const std::uint64_t quotes = x ^ (kOnes * '"');
      const std::uint64_t backslash = x ^ (kOnes * '\\');
      // Standard "has a byte below n" / "has a zero byte" tests: exact as to
      // whether such a byte exists, which is all that is needed here.
      const std::uint64_t flagged = ((x - kOnes * 0x20) & ~x) | ((quotes - kOnes) & ~quotes) |
                                    ((backslash - kOnes) & ~backslash) | x;
      if (flagged & kHighs) return;
      p_ += 8;
    }
  }

  void escape(std::string& out, const char* open) {
    const char* at = p_;
    if (end_ - p_ < 2) fail_at(open, "unterminated string");
    char e = p_[1];
    switch (e) {
      case '"': out += '"'; break;
      case '\\': out += '\\'; break;
      case '/': out += '/'; break;
      case 'b': out += '\b'; break;
      case 'f': out += '\f'; break;
      case 'n': out += '\n'; break;
      case 'r': out += '\r'; break;
      case 't': out += '\t'; break;
      case 'u': {
        std::uint32_t cp = unicode_escape();
        if (cp >= 0xDC00 && cp <= 0xDFFF) fail_at(at, "unpaired low surrogate in \\u escape");
        if (cp >= 0xD800 && cp <= 0xDBFF) {
          if (end_ - p_ < 2 || p_[0] != '\\' || p_[1] != 'u') {
            fail_at(at, "unpaired high surrogate in \\u escape");
          }
          const char* low_at = p_;
          std::uint32_t low = unicode_escape();
          if (low < 0xDC00 || low > 0xDFFF) {
            fail_at(low_at, "expected a low surrogate \\u escape after a high surrogate");
          }
          cp = 0x10000 + ((cp - 0xD800) << 10) + (low - 0xDC00);
        }
        append_utf8(out, cp);
        return;
      }
      default: {
        unsigned char u = static_cast<unsigned char>(e);
        fail_at(at, "invalid escape " +
                        (u >= 0x20 && u < 0x7F ? std::string("'\\") + e + "'" : describe_char(u)));
      }
    }
    p_ += 2;
  }

  Value number() {
    const char* start = p_;
    if (*p_ == '-') ++p_;
    if (p_ == end_ || !is_digit(*p_)) fail_at(p_, "expected a digit after '-'");
    if (*p_ == '0') {
      ++p_;
      if (p_ != end_ && is_digit(*p_)) fail_at(start, "leading zero in number");
    } else {
      while (p_ != end_ && is_digit(*p_)) ++p_;
    }
    if (p_ != end_ && *p_ == '.') {
      ++p_;
      if (p_ == end_ || !is_digit(*p_)) fail_at(p_, "expected a digit after '.'");
      while (p_ != end_ && is_digit(*p_)) ++p_;
    }
    if (p_ != end_ && (*p_ == 'e' || *p_ == 'E')) {
      ++p_;
      if (p_ != end_ && (*p_ == '+' || *p_ == '-')) ++p_;
      if (p_ == end_ || !is_digit(*p_)) fail_at(p_, "expected a digit in the exponent");
      while (p_ != end_ && is_digit(*p_)) ++p_;
    }
    double v = 0;
    auto res = std::from_chars(start, p_, v, std::chars_format::general);
    if (res.ec == std::errc::result_out_of_range) {
      if (magnitude_overflows(start, p_)) fail_at(start, "number is too large for a double");
      v = (*start == '-') ? -0.0 : 0.0;  // underflow: the nearest double is zero
    } else if (res.ec != std::errc() || res.ptr != p_) {
      fail_at(start, "malformed number");
    }
    return Value::make_number(std::string(start, p_), v);
  }

  // Distinguishes overflow from underflow when from_chars reports out of range:
  // the decimal exponent of the leading significant digit decides.
  static bool magnitude_overflows(const char* s, const char* e) {
    if (*s == '-') ++s;
    long long lead = 0;  // power of ten of the first non-zero digit
    bool found = false;
    long long int_digits = 0;
    const char* q = s;
    while (q != e && is_digit(*q)) {
      if (!found && *q != '0') {
        found = true;
        lead = -int_digits;  // corrected below once the integer length is known
      }
      ++int_digits;
      ++q;
    }
    if (found) {
      lead += int_digits - 1;
    }
    if (q != e && *q == '.') {
      ++q;
      long long pos = 0;
      while (q != e && is_digit(*q)) {
        ++pos;
        if (!found && *q != '0') {
          found = true;
          lead = -pos;
        }
        ++q;
      }
    }
    long long exp = 0;
    if (q != e && (*q == 'e' || *q == 'E')) {
      ++q;
      bool neg = false;
      if (*q == '+' || *q == '-') neg = (*q++ == '-');
      while (q != e) {
        if (exp < 1000000000) exp = exp * 10 + (*q - '0');
        ++q;
      }
      if (neg) exp = -exp;
    }
    return found && lead + exp > 0;
  }

  const char* begin_;
  const char* p_;
  const char* end_;
  const std::string& source_;
  std::vector<Value> values_;                             // open arrays' items
  std::vector<std::pair<std::string, Value>> members_;    // open objects' members
};

}  // namespace

bool Value::boolean() const {
  if (type_ != Type::Bool) wrong_type(type_, Type::Bool);
  return b_;
}

double Value::number() const {
  if (type_ != Type::Number) wrong_type(type_, Type::Number);
  return num_;
}

const std::string& Value::number_text() const {
  if (type_ != Type::Number) wrong_type(type_, Type::Number);
  return text_;
}

bool Value::as_u64(std::uint64_t* out) const {
  if (type_ != Type::Number || text_.empty()) return false;
  // "0" is the only integer that may start with a zero; the parser enforces it,
  // values built with make_number are checked the same way here.
  if (text_.size() > 1 && text_[0] == '0') return false;
  std::uint64_t v = 0;
  for (char c : text_) {
    if (!is_digit(c)) return false;
    std::uint64_t d = static_cast<std::uint64_t>(c - '0');
    if (v > (UINT64_MAX - d) / 10) return false;
    v = v * 10 + d;
  }
  *out = v;
  return true;
}

const std::string& Value::str() const {
  if (type_ != Type::String) wrong_type(type_, Type::String);
  return text_;
}

const std::vector<Value>& Value::array() const {
  if (type_ != Type::Array) wrong_type(type_, Type::Array);
  return items_;
}

const std::vector<std::pair<std::string, Value>>& Value::object() const {
  if (type_ != Type::Object) wrong_type(type_, Type::Object);
  return members_;
}

const Value* Value::get(std::string_view key) const {
  if (type_ != Type::Object) wrong_type(type_, Type::Object);
  for (const auto& m : members_) {
    if (m.first == key) return &m.second;
  }
  return nullptr;
}

using Members = std::vector<std::pair<std::string, Value>>;

void Value::destroy() noexcept {
  switch (type_) {
    case Type::Number:
    case Type::String: text_.~basic_string(); break;
    case Type::Array: items_.~vector(); break;
    case Type::Object: members_.~Members(); break;
    default: break;
  }
  type_ = Type::Null;
}

void Value::construct_from(const Value& o) {
  switch (o.type_) {
    case Type::Number:
    case Type::String: new (&text_) std::string(o.text_); break;
    case Type::Array: new (&items_) std::vector<Value>(o.items_); break;
    case Type::Object: new (&members_) Members(o.members_); break;
    default: break;
  }
  type_ = o.type_;
  b_ = o.b_;
  num_ = o.num_;
}

void Value::construct_from(Value&& o) noexcept {
  switch (o.type_) {
    case Type::Number:
    case Type::String: new (&text_) std::string(std::move(o.text_)); break;
    case Type::Array: new (&items_) std::vector<Value>(std::move(o.items_)); break;
    case Type::Object: new (&members_) Members(std::move(o.members_)); break;
    default: break;
  }
  type_ = o.type_;
  b_ = o.b_;
  num_ = o.num_;
}

Value::Value(const Value& other) : type_(Type::Null) { construct_from(other); }
Value::Value(Value&& other) noexcept : type_(Type::Null) { construct_from(std::move(other)); }
Value::~Value() { destroy(); }

// Both assignments go through a temporary: `other` may live inside *this
// (v = v.array()[0]) and must survive destroy().
Value& Value::operator=(const Value& other) {
  if (this != &other) {
    Value tmp(other);
    destroy();
    construct_from(std::move(tmp));
  }
  return *this;
}

Value& Value::operator=(Value&& other) noexcept {
  if (this != &other) {
    Value tmp(std::move(other));
    destroy();
    construct_from(std::move(tmp));
  }
  return *this;
}

Value Value::make_null() { return Value(); }

Value Value::make_bool(bool b) {
  Value v;
  v.type_ = Type::Bool;
  v.b_ = b;
  return v;
}

Value Value::make_number(std::string text, double num) {
  Value v;
  new (&v.text_) std::string(std::move(text));
  v.type_ = Type::Number;
  v.num_ = num;
  return v;
}

Value Value::make_string(std::string s) {
  Value v;
  new (&v.text_) std::string(std::move(s));
  v.type_ = Type::String;
  return v;
}

Value Value::make_array(std::vector<Value> items) {
  Value v;
  new (&v.items_) std::vector<Value>(std::move(items));
  v.type_ = Type::Array;
  return v;
}

Value Value::make_object(std::vector<std::pair<std::string, Value>> members) {
  Value v;
  new (&v.members_) Members(std::move(members));
  v.type_ = Type::Object;
  return v;
}

Value parse(std::string_view text, const std::string& source) {
  return Parser(text, source).document();
}

Value parse_file(const std::string& path) {
  weights::FileBuffer bytes;
  std::string problem = weights::read_file(path, kMaxFileBytes, &bytes);
  if (!problem.empty()) throw Error(path + ": " + problem);
  return parse(std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()), path);
}

std::string quote(std::string_view s) {
  static const char* digits = "0123456789abcdef";
  std::string out;
  out.reserve(s.size() + 2);
  out += '"';
  const auto* p = reinterpret_cast<const unsigned char*>(s.data());
  const auto* end = p + s.size();
  while (p < end) {
    unsigned char c = *p;
    if (c >= 0x80) {
      std::size_t len = utf8_sequence_length(p, end);
      if (len == 0) {
        throw Error("json::quote: invalid UTF-8 byte " + hex_byte(c) + " at offset " +
                    std::to_string(p - reinterpret_cast<const unsigned char*>(s.data())));
      }
      out.append(reinterpret_cast<const char*>(p), len);
      p += len;
      continue;
    }
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\b': out += "\\b"; break;
      case '\f': out += "\\f"; break;
      case '\n': out += "\\n"; break;
      case '\r': out += "\\r"; break;
      case '\t': out += "\\t"; break;
      default:
        if (c < 0x20) {
          out += "\\u00";
          out += digits[c >> 4];
          out += digits[c & 15];
        } else {
          out += static_cast<char>(c);
        }
    }
    ++p;
  }
  out += '"';
  return out;
}

}  // namespace json
