#include "shle/detector_box_source.h"

#include <algorithm>
#include <cmath>

#include "nn/error.h"
#include "shle/error.h"

namespace shle {

namespace det = nn::detection;

std::vector<Candidate> detections_to_candidates(const det::Detections& d, const std::vector<int>& labels,
                                                double score_threshold) {
  std::vector<Candidate> out;
  const std::size_t n = std::min({d.boxes.size(), d.scores.size(), d.labels.size()});
  for (std::size_t i = 0; i < n; ++i) {
    const std::int64_t label = d.labels[i];
    const bool wanted = labels.empty() ? label >= 1
                                       : std::find(labels.begin(), labels.end(), label) != labels.end();
    // In float32 like the RoI heads' own threshold (torchvision compares the float32
    // scores with the threshold cast to float32): 0.3f must not pass "> 0.3".
    if (!wanted || !(d.scores[i] > static_cast<float>(score_threshold))) continue;
    const det::Box& b = d.boxes[i];
    Box box{b.x1, b.y1, b.x2, b.y2};
    // `!(a > b)` also drops NaN corners.
    if (!box.finite() || !(box.x1 > box.x0) || !(box.y1 > box.y0)) continue;
    out.push_back(Candidate{box, d.scores[i]});
  }
  return out;
}

void rgb_to_chw01(const RgbImage& img, std::vector<float>* out) {
  const std::size_t plane = static_cast<std::size_t>(img.width) * static_cast<std::size_t>(img.height);
  out->resize(3 * plane);
  float* r = out->data();
  float* g = r + plane;
  float* b = g + plane;
  const std::uint8_t* p = img.rgb.data();
  // torchvision's to_tensor divides by 255 (float32 division, not a multiply by 1/255).
  for (std::size_t i = 0; i < plane; ++i, p += 3) {
    r[i] = static_cast<float>(p[0]) / 255.0f;
    g[i] = static_cast<float>(p[1]) / 255.0f;
    b[i] = static_cast<float>(p[2]) / 255.0f;
  }
}

namespace {

det::FasterRcnnConfig config_for(det::FasterRcnnVariant v, const DetectorOptions& opt, const std::string& source) {
  if (!(opt.score_threshold >= 0 && opt.score_threshold < 1))
    throw Error(source + ": detector score threshold " + std::to_string(opt.score_threshold) +
                " is outside [0, 1)");
  det::FasterRcnnConfig cfg = det::faster_rcnn_defaults(v);
  cfg.roi_heads.score_thresh = static_cast<float>(opt.score_threshold);
  return cfg;
}

}  // namespace

DetectorBoxSource::DetectorBoxSource(const std::string& weights_path, det::FasterRcnnVariant variant,
                                     const DetectorOptions& options)
    : DetectorBoxSource(weights::SafeTensors::load(weights_path), variant, options) {}

DetectorBoxSource::DetectorBoxSource(const weights::SafeTensors& st, det::FasterRcnnVariant variant,
                                     const DetectorOptions& options)
    : source_(st.source()), options_(options) {
  const det::FasterRcnnConfig cfg = config_for(variant, options, source_);
  // The FasterRcnn constructor names st.source() and the first bad tensor.
  model_ = std::make_unique<det::FasterRcnn>(st, variant, cfg);
  const int classes = model_->num_classes();
  if (options.labels.empty()) {
    for (int l = 1; l < classes; ++l) labels_.push_back(l);
    if (labels_.empty())
      throw Error(source_ + ": the detector holds only the background class (" + std::to_string(classes) +
                  " class), no label can be a height-limit device");
  } else {
    for (int l : options.labels) {
      if (l == 0) throw Error(source_ + ": label 0 is the background, not a device");
      if (l < 0 || l >= classes)
        throw Error(source_ + ": label " + std::to_string(l) + " asked for, but the weights hold " +
                    std::to_string(classes) + " classes (labels 0.." + std::to_string(classes - 1) +
                    ", 0 = background): more classes than the weights hold");
      if (std::find(labels_.begin(), labels_.end(), l) == labels_.end()) labels_.push_back(l);
    }
  }
}

const RgbImage& detector_frame_image(const FrameContext& frame, std::string* where) {
  *where = frame.files ? frame.files->image : "frame " + std::to_string(frame.index);
  if (!frame.image) throw Error(*where + ": the detector needs the decoded image");
  const RgbImage& img = *frame.image;
  if (img.width <= 0 || img.height <= 0 ||
      img.rgb.size() != static_cast<std::size_t>(img.width) * static_cast<std::size_t>(img.height) * 3)
    throw Error(*where + ": image buffer does not hold " + std::to_string(img.width) + "x" +
                std::to_string(img.height) + " RGB pixels");
  return img;
}

std::vector<Candidate> DetectorBoxSource::candidates(const FrameContext& frame) {
  std::string where;
  const RgbImage& img = detector_frame_image(frame, &where);
  try {
    plan_for_frame(*model_, img.width, img.height, &planned_w_, &planned_h_);
    rgb_to_chw01(img, &chw_);
    last_ = model_->forward(chw_.data());
  } catch (const nn::Error& e) {
    throw Error(where + ": " + e.what());
  }
  return detections_to_candidates(last_, labels_, options_.score_threshold);
}

}  // namespace shle
