// StixelNExT++ from an RGB image to a Stixel World: preprocessing (normalisation
// mode, bilinear resize to the network's input size), the network (nn::StixelNExT)
// and the extraction. Settings come from the weights' __metadata__ (keys below),
// overridable by the caller:
//   stixelnext.input_height / stixelnext.input_width   network input (1280 x 1920)
//   stixelnext.columns / stixelnext.stixel_width       U and pixels per column (W / 8, 8)
//   stixelnext.anchors        "tangent:4,66,64" (default) or "linear:START,END,N"
//   stixelnext.normalization  raw255 (default, as trained), unit or imagenet
//   stixelnext.head           v0..v4 to force a head variant (V1 and V3 look alike)
// stixel/model_file.h reads them from a weights file (checking a declared head
// against the tensors) and holds the named presets (waymo, coopscenes).
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "nn/buffer.h"
#include "nn/models/stixelnext.h"
#include "stixel/anchors.h"
#include "stixel/extract.h"
#include "stixel/world.h"

namespace stixel {

enum class Normalization { Raw255, Unit, ImageNet };
const char* normalization_name(Normalization n);
bool parse_normalization(const std::string& text, Normalization* out);

struct ModelSettings {
  int input_height = 1280, input_width = 1920;
  int columns = 0;  // 0: input_width / stixel_width
  int stixel_width = 8;
  Anchors anchors = tangent_anchors();
  Normalization normalization = Normalization::Raw255;
  std::optional<nn::StixelHeadVariant> head;
  nn::Precision precision = nn::Precision::F32;  // a run option, never read from metadata
  int effective_columns() const { return columns > 0 ? columns : input_width / stixel_width; }
};

// Settings from stixelnext.* metadata keys (others ignored); errors name `source`.
ModelSettings settings_from_metadata(const std::map<std::string, std::string>& metadata,
                                     const std::string& source);

// K for an image resized from (w0, h0) to (w1, h1) with align_corners=False:
// pixel centres map as x1 + 0.5 = (x0 + 0.5) * w1 / w0.
std::vector<float> scale_intrinsics(const std::vector<float>& K, int w0, int h0, int w1, int h1);

class Predictor {
 public:
  Predictor(const weights::SafeTensors& st, const ModelSettings& settings);
  // On a loaded, never planned model (settings.head and .precision are the model's):
  // the copy shares its packed weights (nn/buffer.h) and plans its own arena, so any
  // number of predictors can run one model on as many threads.
  Predictor(const nn::StixelNExT& model, const ModelSettings& settings);
  const ModelSettings& settings() const { return settings_; }
  nn::StixelNExT& model() { return model_; }

  // Converts interleaved RGB8 pixels of any size into the network input (float,
  // normalised, resized bilinearly like F.interpolate(..., align_corners=False)).
  // Row r starts at rgb + r * stride bytes (stride >= 3 * width; the bytes after a
  // row's 3 * width are not read); the rows are read in place, never copied.
  // Returns true if the image had to be resized. Throws Error for a null pointer,
  // an empty size or a stride below 3 * width.
  bool preprocess(const std::uint8_t* rgb, int width, int height, std::size_t stride);
  // Contiguous rows (stride 3 * width).
  bool preprocess(const std::uint8_t* rgb, int width, int height);
  // Runs the network on the preprocessed input; returns [A, 64, U].
  const float* run_network();
  // Stixels of the last network run (extract() with the model's settings).
  StixelWorld extract(double threshold, double depth_scale = 1.0) const;

 private:
  ModelSettings settings_;
  nn::StixelNExT model_;
  nn::AlignedBuffer image_, resized_, input_;
  const float* prediction_ = nullptr;
};

}  // namespace stixel
