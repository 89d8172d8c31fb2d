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

}  // namespace testutil
