// shle::parse_labelme on json::parse of arbitrary text (both under the contract).
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "shle/labelme.h"
#include "tests/fuzz/fuzz_contract.h"
#include "weights/json.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string_view text(reinterpret_cast<const char*>(data), size);
  fuzz::run([&] {
    json::Value root = json::parse(text, "fuzz.json");
    (void)shle::parse_labelme(root, "fuzz.json", "height");
  });
  return 0;
}
