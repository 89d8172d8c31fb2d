// The error contract every fuzz harness checks (tests/fuzz/fuzz_*.cpp): a parser of
// outside bytes either returns or throws one of the project's error types, and the
// message is one line (no byte < 0x20 nor 0x7F), non-empty and at most
// kMaxMessageBytes long. Anything else (std::bad_alloc, std::out_of_range,
// std::invalid_argument, a non-std exception, a bad message) aborts, so libFuzzer
// reports it as a crash and keeps the input.
#pragma once

#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <stdexcept>
#include <string>
#include <typeinfo>

#include "geometry/error.h"
#include "nn/error.h"
#include "shle/error.h"
#include "stixel/error.h"
#include "weights/error.h"
#include "weights/json.h"

namespace fuzz {

constexpr std::size_t kMaxMessageBytes = 1024;

[[noreturn]] inline void contract_violation(const char* problem, const char* type, const char* what) {
  std::fprintf(stderr, "fuzz contract violated: %s (exception type %s)\nmessage: ", problem, type);
  // Printed escaped: the message itself may be what breaks the contract.
  std::size_t n = std::strlen(what);
  for (std::size_t i = 0; i < n && i < 4096; ++i) {
    unsigned char c = static_cast<unsigned char>(what[i]);
    if (c < 0x20 || c == 0x7F || c == '\\')
      std::fprintf(stderr, "\\x%02x", c);
    else
      std::fputc(c, stderr);
  }
  std::fputc('\n', stderr);
  std::abort();
}

// The message rules, for exceptions of an accepted type.
inline void check_message(const std::exception& e) {
  const char* what = e.what();
  std::size_t n = std::strlen(what);
  if (n == 0) contract_violation("empty error message", typeid(e).name(), what);
  if (n > kMaxMessageBytes) contract_violation("error message longer than 1024 bytes", typeid(e).name(), what);
  for (std::size_t i = 0; i < n; ++i) {
    unsigned char c = static_cast<unsigned char>(what[i]);
    if (c < 0x20 || c == 0x7F)
      contract_violation("control character in error message", typeid(e).name(), what);
  }
}

inline bool is_project_error(const std::exception& e) {
  return dynamic_cast<const weights::Error*>(&e) || dynamic_cast<const json::Error*>(&e) ||
         dynamic_cast<const stixel::Error*>(&e) || dynamic_cast<const shle::Error*>(&e) ||
         dynamic_cast<const geometry::Error*>(&e) || dynamic_cast<const nn::Error*>(&e);
}

// What a harness may additionally accept: its own error types (Extra... below) and,
// for code documented to throw exactly std::runtime_error (apps/stixelnext), that.
enum class Plain { Reject, AcceptRuntimeError };

// Runs f(); returns true if it returned, false if it threw an accepted error with a
// good message; aborts on anything else.
template <class... Extra, class F>
bool run(F&& f, Plain plain = Plain::Reject) {
  try {
    f();
    return true;
  } catch (const std::exception& e) {
    bool ok = is_project_error(e) || (false || ... || (dynamic_cast<const Extra*>(&e) != nullptr)) ||
              (plain == Plain::AcceptRuntimeError && typeid(e) == typeid(std::runtime_error));
    if (!ok) contract_violation("exception of a type the parser must not throw", typeid(e).name(), e.what());
    check_message(e);
    return false;
  } catch (...) {
    contract_violation("non-std exception", "(unknown)", "");
  }
}

}  // namespace fuzz
