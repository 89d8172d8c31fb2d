// json::parse on arbitrary text. Beyond the error contract: every string of a parsed
// document (keys included) must survive json::quote and parse back unchanged.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "tests/fuzz/fuzz_contract.h"
#include "weights/json.h"

namespace {

void check_string(const std::string& s) {
  std::string quoted = json::quote(s);
  json::Value back = json::parse(quoted, "quoted");
  if (!back.is_string() || back.str() != s) {
    std::fprintf(stderr, "json::quote/parse round trip changed a string\n");
    std::abort();
  }
}

void walk(const json::Value& v, int depth) {
  if (depth > 64) {  // the parser promises to reject deeper nesting
    std::fprintf(stderr, "parsed document nests deeper than 64\n");
    std::abort();
  }
  switch (v.type()) {
    case json::Value::Type::String: check_string(v.str()); break;
    case json::Value::Type::Number: {
      std::uint64_t u = 0;
      (void)v.as_u64(&u);
      (void)v.number();
      break;
    }
    case json::Value::Type::Array:
      for (const json::Value& e : v.array()) walk(e, depth + 1);
      break;
    case json::Value::Type::Object:
      for (const auto& m : v.object()) {
        check_string(m.first);
        if (v.get(m.first) != &m.second) {  // keys are unique
          std::fprintf(stderr, "object lookup does not find its own member\n");
          std::abort();
        }
        walk(m.second, depth + 1);
      }
      break;
    default: break;
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string_view text(reinterpret_cast<const char*>(data), size);
  fuzz::run([&] { walk(json::parse(text, "fuzz.json"), 1); });
  return 0;
}
