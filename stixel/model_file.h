// What a StixelNExT++ weights file says about itself: its stixelnext.* metadata
// (predictor.h lists the keys), checked against its tensors, and the named
// presets of the published setups, usable at export (weights/export.py --preset)
// and at run time (stixelnext --preset, roadnn_model_params).
//
//   waymo       1280 x 1920 input, 240 columns of 8 px, raw 0..255, tangent:4,66,64
//   coopscenes  1200 x 1920 input, 120 columns of 16 px, ImageNet mean/std, tangent:4,66,64
//
// weights/export.py holds the same table for writing files; a test checks that
// the two agree (stixelnext_cli_tests, ExportPresetsAreTheLibrarys).
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "nn/models/stixel_head.h"
#include "stixel/predictor.h"
#include "weights/safetensors.h"

namespace stixel {

// The preset names, in documentation order.
std::vector<std::string> preset_names();
// The stixelnext.* metadata of a preset; false for an unknown name.
bool preset_metadata(const std::string& name, std::map<std::string, std::string>* out);

// Applies stixelnext.* keys of `metadata` over `settings` (other keys ignored);
// errors name `source` and the key.
void apply_metadata(const std::map<std::string, std::string>& metadata, const std::string& source,
                    ModelSettings* settings);

// The head layout the tensors under "classifier." have: V4, V1 (standing for V1
// or V3, which share their tensors), V2 or V0. Throws weights::Error when none fits.
nn::StixelHeadVariant head_layout(const weights::SafeTensors& st);

// settings_from_metadata() of the file's own metadata, after checking that a
// declared stixelnext.head fits the tensors: a file that says v4 but holds a
// V1/V3 head (or any other contradiction) is an Error naming the key and the
// tensor that disagrees. V1 and V3 fit the same tensors.
ModelSettings settings_from_weights(const weights::SafeTensors& st);

// When the tensors fit both V1 and V3 and `head` (the file's metadata or the
// caller's choice) says neither, the one-line warning to print once per run
// (naming both variants and the fix); empty otherwise.
std::string head_ambiguity_warning(const weights::SafeTensors& st, const std::optional<nn::StixelHeadVariant>& head);

}  // namespace stixel
