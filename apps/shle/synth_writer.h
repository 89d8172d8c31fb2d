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

// The SmarterEye calibration pair the released code reads (shle.md section 2.2)
// for `cal`: DIR/calibData.json with fx at [4], fy at [12], cy at [40] and [42],
// cx + 10 at [39] and [41]; DIR/DepthCalib.json with 4 at [0] and 6.5 at [4]
// (floor(6.5 + 4) = 10 px taken back off cx); bf, mount height and the disparity
// scale are the released constants (240, 1.45, 32), which the synthetic camera uses.
void write_smartereye_params(const shle::Calibration& cal, const std::string& dir);

}  // namespace shleapp
