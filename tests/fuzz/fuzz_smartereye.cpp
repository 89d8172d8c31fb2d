// shle::parse_smartereye_calibration (the SmarterEye calibData.json + DepthCalib.json
// pair). The input holds calibData.json, a NUL byte, then DepthCalib.json (JSON text
// cannot hold a raw NUL); without a NUL, DepthCalib.json is a fixed valid one.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "shle/calibration.h"
#include "tests/fuzz/fuzz_contract.h"
#include "weights/json.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string_view text(reinterpret_cast<const char*>(data), size);
  std::string_view calib = text, depth = R"({"data": [1.5, 0, 0, 0, 2.25]})";
  if (std::size_t nul = text.find('\0'); nul != std::string_view::npos) {
    calib = text.substr(0, nul);
    depth = text.substr(nul + 1);
  }
  fuzz::run([&] {
    json::Value c = json::parse(calib, "calibData.json");
    json::Value d = json::parse(depth, "DepthCalib.json");
    (void)shle::parse_smartereye_calibration(c, "calibData.json", d, "DepthCalib.json");
  });
  return 0;
}
