// Writes a synthetic scene (shle/synth.h) as a sequence folder that `shle` reads:
// images, LabelMe annotations, disparity files, calib.json, truth.json and the
// simulated detector's detections.csv.
#pragma once

#include <functional>
#include <string>

#include "shle/synth.h"

namespace shleapp {

enum class SynthLayout { Released, PlainDat, PlainPfm };

// Throws on I/O errors. `progress(done, total)` after every frame.
void write_synth_scene(const shle::synth::Scene& scene, const std::string& dir, SynthLayout layout,
                       const std::function<void(int, int)>& progress = {});

}  // namespace shleapp
