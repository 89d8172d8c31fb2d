// How tensor names appear inside error messages: in single quotes, with control
// characters escaped so a hostile name cannot break the one-line message.
#pragma once

#include <string>

namespace weights {

inline std::string quote_name(const std::string& name) {
  static const char* digits = "0123456789abcdef";
  std::string out = "'";
  for (char ch : name) {
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
