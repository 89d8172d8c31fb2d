// Decimal text of the CSV-like files stixel writes (stixels, points): the shortest
// text that parses back to the same float32, and plain integers; one definition so
// every file prints a value the same way.
#pragma once

#include <charconv>
#include <string>

namespace stixel {

inline void append_float(std::string& out, float f) {
  char buf[32];
  auto r = std::to_chars(buf, buf + sizeof buf, f);
  out.append(buf, r.ptr);
}

inline void append_int(std::string& out, long long v) {
  char buf[24];
  auto r = std::to_chars(buf, buf + sizeof buf, v);
  out.append(buf, r.ptr);
}

}  // namespace stixel
