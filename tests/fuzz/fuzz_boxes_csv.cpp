// shle::parse_boxes_csv on arbitrary text.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "shle/boxes_csv.h"
#include "tests/fuzz/fuzz_contract.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string_view text(reinterpret_cast<const char*>(data), size);
  fuzz::run([&] {
    shle::BoxesFile f = shle::parse_boxes_csv(text, "fuzz.csv");
    std::size_t n = 0;
    for (const auto& [frame, boxes] : f.frames) {
      if (frame < 0) std::abort();
      n += boxes.size();
    }
    if (n != f.count) std::abort();
  });
  return 0;
}
