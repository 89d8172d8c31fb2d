// shle::parse_released_stage1 (and has_released_stage1_layout) on json::parse of
// arbitrary text, under the contract: a returned box lies in the image (within the
// documented slack) and has x0 <= x1, y0 <= y1.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "shle/released_boxes.h"
#include "tests/fuzz/fuzz_contract.h"
#include "weights/json.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string_view text(reinterpret_cast<const char*>(data), size);
  fuzz::run([&] {
    json::Value root = json::parse(text, "fuzz.json");
    (void)shle::has_released_stage1_layout(root);
    shle::Box b = shle::parse_released_stage1(root, "fuzz.json", 1280, 720);
    const double s = shle::kReleasedBoxSlack;
    if (!b.finite() || b.x0 > b.x1 || b.y0 > b.y1 || b.x0 < -s || b.y0 < -s || b.x1 > 1280 + s || b.y1 > 720 + s)
      std::abort();
  });
  return 0;
}
