// session_memory: what a second StixelNExT++ session costs, measured as the process's
// resident memory (VmRSS, and the peak VmHWM) through the C API.
//
//   session_memory [--size HxW] [--threads N]
//
// One model (seeded random ConvNeXt-Tiny + V4 head weights, written to a temporary
// file and memory-mapped, as a user's file would be), then one session runs a frame,
// then a second session runs a frame while the first one is kept. Prints the figures
// and checks the bound: peak with two sessions <= 1.1 x (peak with one + one
// session's arena), the arena being what the first session added to the resident set.
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include "nn/models/convnext.h"
#include "nn/models/stixel_head.h"
#include "nn/models/synthetic_weights.h"
#include "roadnn/roadnn.h"

namespace {

double status_mb(const char* key) {
  std::ifstream f("/proc/self/status");
  std::string line;
  const std::string k = std::string(key) + ":";
  while (std::getline(f, line))
    if (line.compare(0, k.size(), k) == 0) return std::atof(line.c_str() + k.size()) / 1024.0;
  return -1;
}

bool ok(roadnn_status s) {
  if (s == ROADNN_OK) return true;
  std::fprintf(stderr, "session_memory: %s\n", roadnn_last_error());
  return false;
}

}  // namespace

int main(int argc, char** argv) {
  int h = 1280, w = 1920, threads = 2;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--size" && i + 1 < argc && std::sscanf(argv[i + 1], "%dx%d", &h, &w) == 2) {
      ++i;
    } else if (a == "--threads" && i + 1 < argc) {
      threads = std::atoi(argv[++i]);
    } else {
      std::fprintf(stderr, "usage: session_memory [--size HxW] [--threads N]\n");
      return a == "--help" ? 0 : 2;
    }
  }
  const std::string path = "/tmp/roadnn_session_memory_" + std::to_string(getpid()) + ".safetensors";
  {
    auto specs = nn::convnext_tensor_specs(nn::convnext_tiny_config(), "features.");
    for (auto& s : nn::stixel_head_tensor_specs(nn::StixelHeadVariant::V4, 768, "classifier.")) specs.push_back(s);
    weights::Writer wr = nn::synthetic_weights(specs, 7);
    wr.set_metadata("stixelnext.input_height", std::to_string(h));
    wr.set_metadata("stixelnext.input_width", std::to_string(w));
    const auto bytes = wr.bytes();
    std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()), bytes.size());
  }
  const double base = status_mb("VmRSS");
  roadnn_model_params mp = roadnn_model_default_params(ROADNN_MODEL_STIXELNEXT);
  roadnn_model* model = nullptr;
  if (!ok(roadnn_model_load_file(path.c_str(), &mp, &model))) return 1;
  std::remove(path.c_str());
  roadnn_model_info info;
  roadnn_model_get_info(model, &info);
  const double loaded = status_mb("VmRSS"), loaded_peak = status_mb("VmHWM");

  std::vector<std::uint8_t> rgb(static_cast<std::size_t>(w) * h * 3);
  for (std::size_t i = 0; i < rgb.size(); ++i) rgb[i] = static_cast<std::uint8_t>((i * 2654435761u) >> 24);
  const roadnn_image image{rgb.data(), w, h, 0};
  roadnn_session_params sp = roadnn_session_default_params();
  sp.threads = threads;
  roadnn_session *s1 = nullptr, *s2 = nullptr;
  roadnn_stixel_world world;
  if (!ok(roadnn_session_create(model, &sp, &s1)) || !ok(roadnn_stixel_run(s1, &image, nullptr, nullptr, &world)))
    return 1;
  const double one = status_mb("VmRSS"), one_peak = status_mb("VmHWM");
  if (!ok(roadnn_session_create(model, &sp, &s2)) || !ok(roadnn_stixel_run(s2, &image, nullptr, nullptr, &world)) ||
      !ok(roadnn_stixel_run(s1, &image, nullptr, nullptr, &world)))
    return 1;
  const double two = status_mb("VmRSS"), two_peak = status_mb("VmHWM");
  roadnn_session_free(s2);
  roadnn_session_free(s1);
  roadnn_model_free(model);

  // What the first session added to the resident set (its arena and buffers); the
  // loading peak is transient (the mapped file, the unpacked tensors) and excluded.
  const double arena = one - loaded;
  const double bound = 1.1 * (one_peak + arena);
  std::printf("StixelNExT++ %dx%d, %d threads, kernels %s\n", h, w, threads, info.kernels);
  std::printf("  packed weights (shared)      %8.1f MB\n", info.weight_bytes / 1e6 * (1e6 / 1048576.0));
  std::printf("  process before loading       %8.1f MB RSS\n", base);
  std::printf("  model loaded                 %8.1f MB RSS (peak %.1f)\n", loaded, loaded_peak);
  std::printf("  + session 1 run              %8.1f MB RSS (peak %.1f): one session's arena %.1f MB\n", one,
              one_peak, arena);
  std::printf("  + session 2 run              %8.1f MB RSS (peak %.1f)\n", two, two_peak);
  std::printf("  second session cost          %8.1f MB (peak %.1f MB)\n", two - one, two_peak - one_peak);
  std::printf("  bound 1.1 x (one + arena)    %8.1f MB: %s\n", bound, two_peak <= bound ? "met" : "NOT met");
  return two_peak <= bound ? 0 : 1;
}
