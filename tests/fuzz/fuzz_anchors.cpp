// stixel::parse_anchor_spec on arbitrary text; a spec that parses must describe
// itself (anchor_spec) in a form that parses again to the same depths.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "stixel/anchors.h"
#include "tests/fuzz/fuzz_contract.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string spec(reinterpret_cast<const char*>(data), size);
  stixel::Anchors a;
  if (!fuzz::run([&] { a = stixel::parse_anchor_spec(spec, "--anchors"); })) return 0;
  fuzz::run([&] {
    stixel::Anchors b = stixel::parse_anchor_spec(stixel::anchor_spec(a), "anchor_spec()");
    if (b.kind != a.kind || b.depth.size() != a.depth.size()) {
      std::fprintf(stderr, "anchor_spec() does not read back\n");
      std::abort();
    }
  });
  return 0;
}
