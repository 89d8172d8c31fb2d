// shle::parse_gt_heights and shle::parse_gt_height_args on arbitrary text, under
// the contract: every entry has a scene id >= 1 and a height in (0, 100].
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <map>
#include <string_view>

#include "shle/disparity_height.h"
#include "tests/fuzz/fuzz_contract.h"

namespace {

void check(const std::map<int, double>& t) {
  for (const auto& [id, h] : t)
    if (id < 1 || !(h > 0 && h <= 100)) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string_view text(reinterpret_cast<const char*>(data), size);
  fuzz::run([&] { check(shle::parse_gt_heights(text, "fuzz.csv")); });
  fuzz::run([&] {
    std::map<int, double> t;
    shle::parse_gt_height_args(text, &t);
    check(t);
  });
  return 0;
}
