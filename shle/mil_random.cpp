#include "shle/mil_random.h"

namespace shle {

void GlibcRand::reseed(std::uint32_t seed) {
  // srandom_r for TYPE_3: a Lehmer sequence (16807 mod 2^31 - 1, Schrage's
  // method) fills the 31 words, then 310 outputs are discarded.
  if (seed == 0) seed = 1;
  std::int64_t word = seed;  // glibc keeps it in a long
  state_[0] = static_cast<std::int32_t>(seed);
  for (int i = 1; i < 31; ++i) {
    const std::int64_t hi = word / 127773, lo = word % 127773;
    word = 16807 * lo - 2836 * hi;
    if (word < 0) word += 2147483647;
    state_[i] = static_cast<std::int32_t>(word);
  }
  front_ = 3;
  rear_ = 0;
  for (int i = 0; i < 310; ++i) next();
}

int GlibcRand::next() {
  // random_r: the front word accumulates the rear one (unsigned wrap-around).
  const std::uint32_t v =
      static_cast<std::uint32_t>(state_[front_]) + static_cast<std::uint32_t>(state_[rear_]);
  state_[front_] = static_cast<std::int32_t>(v);
  front_ = front_ == 30 ? 0 : front_ + 1;
  rear_ = rear_ == 30 ? 0 : rear_ + 1;
  return static_cast<int>(v >> 1);
}

}  // namespace shle
