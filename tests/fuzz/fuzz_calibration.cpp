// shle::parse_calibration (the plain JSON calibration of the height stage) on
// json::parse of arbitrary text.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "shle/calibration.h"
#include "tests/fuzz/fuzz_contract.h"
#include "weights/json.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string_view text(reinterpret_cast<const char*>(data), size);
  fuzz::run([&] { (void)shle::parse_calibration(json::parse(text, "calib.json"), "calib.json"); });
  return 0;
}
