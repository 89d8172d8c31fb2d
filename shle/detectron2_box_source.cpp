#include "shle/detectron2_box_source.h"

#include <algorithm>

#include "nn/error.h"
#include "shle/error.h"

namespace shle {

namespace det = nn::detection;

Detectron2BoxSource::Detectron2BoxSource(const std::string& weights_path, const DetectorOptions& options)
    : Detectron2BoxSource(weights::SafeTensors::load(weights_path), options) {}

Detectron2BoxSource::Detectron2BoxSource(const weights::SafeTensors& st, const DetectorOptions& options)
    : source_(st.source()), options_(options) {
  if (!(options.score_threshold >= 0 && options.score_threshold < 1))
    throw Error(source_ + ": detector score threshold " + std::to_string(options.score_threshold) +
                " is outside [0, 1)");
  // The RoI heads' own threshold at the candidates' (see DetectorOptions).
  det::Detectron2FasterRcnnConfig cfg;
  cfg.roi_heads.score_thresh = static_cast<float>(options.score_threshold);
  model_ = std::make_unique<det::Detectron2FasterRcnn>(st, cfg);
  const int k = model_->num_classes();
  if (options.labels.empty())
    for (int l = 0; l < k; ++l) labels_.push_back(l);
  for (int l : options.labels) {
    if (l < 0 || l >= k)
      throw Error(source_ + ": label " + std::to_string(l) + " asked for, but the weights hold " + std::to_string(k) +
                  " detectron2 classes (labels 0.." + std::to_string(k - 1) + ")");
    if (std::find(labels_.begin(), labels_.end(), l) == labels_.end()) labels_.push_back(l);
  }
}

std::vector<Candidate> Detectron2BoxSource::candidates(const FrameContext& frame) {
  std::string where;
  const RgbImage& img = detector_frame_image(frame, &where);
  try {
    plan_for_frame(*model_, img.width, img.height, &planned_w_, &planned_h_);
    last_ = model_->forward(img.rgb.data());
  } catch (const nn::Error& e) {
    throw Error(where + ": " + e.what());
  }
  return detections_to_candidates(last_, labels_, options_.score_threshold);
}

}  // namespace shle
