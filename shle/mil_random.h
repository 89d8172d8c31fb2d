// The two random number generators OpenCV 4.6's TrackerMIL draws from, re-created
// so that a MIL tracker can reproduce its features and samples bit for bit while
// keeping its own state (nothing process-global here).
#pragma once

#include <cstdint>

namespace shle {

// glibc's rand(): the TYPE_3 additive feedback generator (x[i] = x[i-31] + x[i-3],
// output x >> 1) behind srand()/rand() of the default 128-byte state. OpenCV's
// Haar features call the process-global rand(); a process that never calls
// srand() (Python, the released scripts) starts from seed 1, and every tracker
// created in that process continues the same sequence.
class GlibcRand {
 public:
  explicit GlibcRand(std::uint32_t seed = 1) { reseed(seed); }
  void reseed(std::uint32_t seed);
  // The next rand() value, 0 .. 2^31 - 1 (RAND_MAX).
  int next();

 private:
  std::int32_t state_[31] = {};
  int front_ = 3, rear_ = 0;
};

// cv::RNG: multiply-with-carry, 64-bit state, coefficient 4164903690. OpenCV's
// thread default (cv::theRNG()) starts at 0xffffffff; the MIL sampler copies it
// when a tracker is initialised, so every tracker starts from that state.
class CvRng {
 public:
  explicit CvRng(std::uint64_t state = 0xffffffffull) : state_(state) {}
  std::uint32_t next() {
    state_ = static_cast<std::uint64_t>(static_cast<std::uint32_t>(state_)) * 4164903690u +
             static_cast<std::uint32_t>(state_ >> 32);
    return static_cast<std::uint32_t>(state_);
  }
  // cv::RNG::uniform(0.f, 1.f): the 32-bit draw as float times 2^-32, in float.
  float uniform01() { return static_cast<float>(next()) * 2.3283064365386962890625e-10f; }

 private:
  std::uint64_t state_;
};

}  // namespace shle
