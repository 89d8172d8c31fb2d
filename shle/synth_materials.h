// Surface materials of the synthetic scenes (internal to the generator).
#pragma once

namespace shle {
namespace synth {

enum Material : int {
  kStripes = 0,   // yellow/black height-limit bar
  kSign,          // white sign with red border and dark lettering
  kPost,          // smooth grey metal: weak texture
  kConcrete,      // bridge face
  kConcreteDark,  // abutments
  kRailing,
  kCable,
  kFoliage,
  kTrunk,
  kFacade,
  kMaterialCount
};

}  // namespace synth
}  // namespace shle
