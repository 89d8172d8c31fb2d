// The message of the exception a call throws, or "" when it returns: error tests
// assert on the wording users will read.
#pragma once

#include <exception>
#include <functional>
#include <string>

namespace testutil {

inline std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

// An error message as users must always see it: non-empty, one line, no control
// characters (so input bytes cannot break it up or carry terminal escapes), bounded.
inline bool is_one_printable_line(const std::string& m, std::size_t max_bytes = 2000) {
  if (m.empty() || m.size() > max_bytes) return false;
  for (unsigned char c : m)
    if (c < 0x20 || c == 0x7f) return false;
  return true;
}

// A hostile field: newline, CR, ESC sequence, DEL and a long tail.
inline std::string hostile_text() { return "a\nb\rc\x1b[31md\x7f" + std::string(5000, 'z'); }

}  // namespace testutil
