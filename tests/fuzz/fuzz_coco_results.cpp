// shle::parse_coco_results and shle::parse_coco_images on json::parse of arbitrary
// text, under the contract: ids >= 1, finite boxes with w, h >= 0, scores in [0, 1],
// non-empty image names without '/'.
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
    if (root.is_array()) {
      for (const shle::CocoDetection& d : shle::parse_coco_results(root, "fuzz.json"))
        if (d.image_id < 1 || !d.box().finite() || d.w < 0 || d.h < 0 || !(d.score >= 0 && d.score <= 1))
          std::abort();
    } else {
      for (const auto& [id, name] : shle::parse_coco_images(root, "fuzz.json"))
        if (id < 1 || name.empty() || name.find('/') != std::string::npos) std::abort();
    }
  });
  return 0;
}
