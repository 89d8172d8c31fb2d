// Two camera streams on two threads sharing one loaded model (C++ API).
//
//   two_streams MODEL.safetensors [FRAMES]
//
// The model's packed weights exist once; each Session holds only its own arena.
// The streams see different synthetic frames; a third, serial pass over the same
// frames checks that running concurrently changed no bit.
#include <cstdio>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include "roadnn/roadnn.hpp"

namespace {

std::vector<std::uint8_t> frame(int w, int h, int seed) {
  std::vector<std::uint8_t> px(static_cast<std::size_t>(w) * h * 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c)
        px[(static_cast<std::size_t>(y) * w + x) * 3 + c] =
            static_cast<std::uint8_t>((x * (c + 1) + y * 3 + seed * 37) % 256);
  return px;
}

// Depths of every stixel of every frame, in order.
std::vector<float> run_stream(roadnn::Session& session, int stream, int frames, int w, int h) {
  std::vector<float> depths;
  for (int i = 0; i < frames; ++i) {
    const std::vector<std::uint8_t> px = frame(w, h, stream * 1000 + i);
    const roadnn_stixel_world world = session.stixels({px.data(), w, h, 0});
    for (std::size_t k = 0; k < world.count; ++k) depths.push_back(world.stixels[k].depth);
  }
  return depths;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s MODEL.safetensors [FRAMES]\n", argv[0]);
    return 2;
  }
  const int frames = argc > 2 ? std::atoi(argv[2]) : 3;
  const int w = 320, h = 192;
  try {
    const roadnn::Model model(argv[1], roadnn::Model::defaults(ROADNN_MODEL_STIXELNEXT));
    for (const std::string& warning : model.warnings()) std::fprintf(stderr, "warning: %s\n", warning.c_str());
    roadnn_session_params sp = roadnn::Session::defaults();
    sp.threads = 1;  // one core per stream
    roadnn::Session left(model, sp), right(model, sp);

    std::vector<float> got[2];
    std::thread a([&] { got[0] = run_stream(left, 0, frames, w, h); });
    std::thread b([&] { got[1] = run_stream(right, 1, frames, w, h); });
    a.join();
    b.join();

    roadnn::Session serial(model, sp);
    bool same = true;
    for (int s = 0; s < 2; ++s) {
      const std::vector<float> want = run_stream(serial, s, frames, w, h);
      same = same && want.size() == got[s].size() &&
             std::memcmp(want.data(), got[s].data(), want.size() * sizeof(float)) == 0;
    }
    const roadnn_model_info info = model.info();
    std::printf("roadnn %s, %s kernels, %.1f MB of shared weights: stream 0 %zu stixels, stream 1 %zu stixels "
                "over %d frames each; concurrent == serial: %s\n",
                roadnn::version().c_str(), info.kernels, info.weight_bytes / 1e6, got[0].size(), got[1].size(),
                frames, same ? "yes" : "NO");
    return same ? 0 : 1;
  } catch (const roadnn::Error& e) {
    std::fprintf(stderr, "%s (%s)\n", e.what(), roadnn_status_name(e.status()));
    return 1;
  }
}
