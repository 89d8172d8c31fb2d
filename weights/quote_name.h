// How text taken from an input (tensor names, JSON keys and values, CSV fields)
// appears inside error messages: in single quotes, control characters and DEL escaped
// as \xNN, and cut after `max_bytes` bytes with "...", so a hostile input can neither
// break a one-line message into several lines, carry terminal escapes, nor make it
// unboundedly long.
#pragma once

#include <cstddef>
#include <string>

namespace weights {

inline std::string quote_name(const std::string& name, std::size_t max_bytes = 120) {
  static const char* digits = "0123456789abcdef";
  std::string out = "'";
  std::size_t used = 0;
  for (char ch : name) {
    if (used++ >= max_bytes) {
      out += "'...";
      return out;
    }
    unsigned char c = static_cast<unsigned char>(ch);
    if (c < 0x20 || c == 0x7F) {
      out += "\\x";
      out += digits[c >> 4];
      out += digits[c & 15];
    } else {
      out += ch;
    }
  }
  out += "'";
  return out;
}

}  // namespace weights
