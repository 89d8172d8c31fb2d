#include "stixel/predictor.h"

#include "weights/quote_name.h"

#include <cstdlib>
#include <cstring>
#include <string>

#include "nn/layout.h"
#include "nn/resize.h"
#include "stixel/error.h"
#include "stixel/model_file.h"

namespace stixel {

const char* normalization_name(Normalization n) {
  switch (n) {
    case Normalization::Raw255: return "raw255";
    case Normalization::Unit: return "unit";
    case Normalization::ImageNet: return "imagenet";
  }
  return "?";
}

bool parse_normalization(const std::string& text, Normalization* out) {
  for (auto n : {Normalization::Raw255, Normalization::Unit, Normalization::ImageNet})
    if (text == normalization_name(n)) {
      *out = n;
      return true;
    }
  return false;
}

ModelSettings settings_from_metadata(const std::map<std::string, std::string>& md, const std::string& source) {
  ModelSettings s;
  apply_metadata(md, source, &s);
  return s;
}

std::vector<float> scale_intrinsics(const std::vector<float>& K, int w0, int h0, int w1, int h1) {
  std::vector<float> k = K;
  const double sx = static_cast<double>(w1) / w0, sy = static_cast<double>(h1) / h0;
  k[0] = static_cast<float>(K[0] * sx);
  k[1] = static_cast<float>(K[1] * sx);
  k[2] = static_cast<float>((K[2] + 0.5) * sx - 0.5);
  k[3] = static_cast<float>(K[3] * sy);
  k[4] = static_cast<float>(K[4] * sy);
  k[5] = static_cast<float>((K[5] + 0.5) * sy - 0.5);
  return k;
}

Predictor::Predictor(const weights::SafeTensors& st, const ModelSettings& settings)
    : Predictor(nn::StixelNExT(st, settings.head, settings.precision), settings) {}

Predictor::Predictor(const nn::StixelNExT& model, const ModelSettings& settings)
    : settings_(settings), model_(model) {
  if (settings_.anchors.size() != nn::StixelHead::kCandidates)
    throw Error("stixelnext: the head predicts 64 candidates but the anchor set has " +
                std::to_string(settings_.anchors.size()));
  model_.plan(1, settings_.input_height, settings_.input_width, settings_.effective_columns());
  input_.resize(static_cast<std::size_t>(3) * settings_.input_height * settings_.input_width);
  resized_.resize(input_.size());
}

bool Predictor::preprocess(const std::uint8_t* rgb, int width, int height, std::size_t stride) {
  static const float kMean[3] = {0.485f, 0.456f, 0.406f}, kStd[3] = {0.229f, 0.224f, 0.225f};
  if (!rgb) throw Error("image: null pixel pointer");
  if (width < 1 || height < 1)
    throw Error("image: size " + std::to_string(width) + "x" + std::to_string(height) + " is empty");
  const std::size_t row = static_cast<std::size_t>(width) * 3;
  if (stride < row)
    throw Error("image: row stride " + std::to_string(stride) + " bytes is less than 3 * width = " +
                std::to_string(row));
  const std::size_t pixels = static_cast<std::size_t>(width) * height;
  if (image_.size() < pixels * 3) image_.resize(pixels * 3);
  float* x = image_.data();
  for (int r = 0; r < height; ++r) {
    const std::uint8_t* src = rgb + static_cast<std::size_t>(r) * stride;
    float* dst = x + static_cast<std::size_t>(r) * row;
    for (std::size_t i = 0; i < row; ++i) {
      const float v = src[i];
      switch (settings_.normalization) {
        case Normalization::Raw255: dst[i] = v; break;
        case Normalization::Unit: dst[i] = v / 255.0f; break;
        case Normalization::ImageNet: dst[i] = (v / 255.0f - kMean[i % 3]) / kStd[i % 3]; break;
      }
    }
  }
  const int h1 = settings_.input_height, w1 = settings_.input_width;
  const bool resize = width != w1 || height != h1;
  const float* nhwc = x;
  if (resize) {
    nn::resize_bilinear(nn::ConstTensorView(x, {1, height, width, 3}), nn::TensorView{resized_.data(), {1, h1, w1, 3}});
    nhwc = resized_.data();
  }
  nn::nhwc_to_nchw(nhwc, 1, 3, h1, w1, input_.data());
  return resize;
}

bool Predictor::preprocess(const std::uint8_t* rgb, int width, int height) {
  return preprocess(rgb, width, height, static_cast<std::size_t>(width > 0 ? width : 0) * 3);
}

const float* Predictor::run_network() {
  prediction_ = model_.forward(input_.data());
  return prediction_;
}

StixelWorld Predictor::extract(double threshold, double depth_scale) const {
  if (!prediction_) throw Error("stixelnext: extract() before run_network()");
  ExtractOptions o;
  o.threshold = threshold;
  o.image_height = settings_.input_height;
  o.stixel_width = settings_.stixel_width;
  o.depth_scale = depth_scale;
  return stixel::extract(prediction_, model_.head().attributes(), nn::StixelHead::kCandidates, model_.columns(),
                         settings_.anchors, o);
}

}  // namespace stixel
