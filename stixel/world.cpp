#include "stixel/world.h"

#include <algorithm>
#include <string>

#include "stixel/error.h"

namespace stixel {

void filter_by_confidence(StixelWorld& world, double min_confidence) {
  if (!(min_confidence >= 0.0 && min_confidence <= 1.0))
    throw Error("confidence filter must be in [0, 1], got " + std::to_string(min_confidence));
  auto& v = world.stixels;
  v.erase(std::remove_if(v.begin(), v.end(),
                         [&](const Stixel& s) {
                           return !(static_cast<double>(s.confidence) >= min_confidence);
                         }),
          v.end());
}

}  // namespace stixel
