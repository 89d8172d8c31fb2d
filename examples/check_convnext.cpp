// A numerics check as a user writes one (C++ API + roadnn/testing.hpp, no GoogleTest):
// run ConvNeXt features on an input and compare them with PyTorch's.
//
//   check_convnext MODEL.safetensors INPUT.f32 N,3,H,W REFERENCE.safetensors [TENSOR [RTOL]]
//
// INPUT.f32 is the raw little-endian float32 NCHW input (numpy: x.astype("<f4").tofile(...));
// REFERENCE holds PyTorch's `model.features(x)` under TENSOR (default "features", the name
// `scripts/torch_dump.py --outputs` writes). Exit status 0 when within RTOL (default
// 1e-4) * max|reference|, 1 when not (the message names the worst element), 2 on errors.
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include "roadnn/roadnn.hpp"
#include "roadnn/testing.hpp"

int main(int argc, char** argv) {
  if (argc < 5 || argc > 7) {
    std::fprintf(stderr, "usage: check_convnext MODEL.safetensors INPUT.f32 N,3,H,W REFERENCE.safetensors "
                         "[TENSOR [RTOL]]\n");
    return 2;
  }
  int n = 0, c = 0, h = 0, w = 0;
  if (std::sscanf(argv[3], "%d,%d,%d,%d", &n, &c, &h, &w) != 4 || n < 1 || c != 3 || h < 1 || w < 1) {
    std::fprintf(stderr, "check_convnext: shape '%s' is not N,3,H,W\n", argv[3]);
    return 2;
  }
  const std::string tensor = argc > 5 ? argv[5] : "features";
  const double rtol = argc > 6 ? std::atof(argv[6]) : 1e-4;

  std::vector<float> input(static_cast<std::size_t>(n) * c * h * w);
  std::ifstream in(argv[2], std::ios::binary);
  in.read(reinterpret_cast<char*>(input.data()), static_cast<std::streamsize>(input.size() * sizeof(float)));
  if (!in || in.peek() != std::char_traits<char>::eof()) {
    std::fprintf(stderr, "check_convnext: %s: not exactly %zu float32 values\n", argv[2], input.size());
    return 2;
  }
  try {
    roadnn::Model model(argv[1], roadnn::Model::defaults(ROADNN_MODEL_CONVNEXT));
    roadnn_session_params sp = roadnn::Session::defaults();
    sp.batch = n;
    sp.height = h;
    sp.width = w;
    roadnn::Session session(model, sp);
    const std::vector<float> features = session.convnext(input);
    const auto result = roadnn::testing::compare(features, session.convnext_output_shape(), argv[4], tensor,
                                                 roadnn::testing::rtol(rtol));
    std::printf("%s: %s\n", result.ok ? "ok" : result.error ? "error" : "FAIL", result.message.c_str());
    return result.ok ? 0 : result.error ? 2 : 1;
  } catch (const roadnn::Error& e) {
    std::fprintf(stderr, "check_convnext: %s\n", e.what());
    return 2;
  }
}
