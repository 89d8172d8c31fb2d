#include "shle/stream.h"

#include <cmath>

#include "shle/box_rules.h"
#include "shle/error.h"

namespace shle {
namespace {

const PipelineOptions& checked(const PipelineOptions& opt, const Calibration& cal) {
  validate(opt);
  if (opt.gate_with_annotations)
    throw Error("gate_with_annotations needs the LabelMe annotations of a sequence (run_sequence); the stream has none");
  if (opt.max_track_frames < 0) throw Error("max_track_frames must be >= 0 (0: no limit)");
  if (cal.width <= 0 || cal.height <= 0) throw Error("calibration width and height must be > 0");
  return opt;
}

std::string frame_name(int index) { return "frame " + std::to_string(index); }

std::string size_text(int w, int h) { return std::to_string(w) + "x" + std::to_string(h); }

}  // namespace

StreamEstimator::StreamEstimator(const Calibration& cal, const PipelineOptions& opt)
    : cal_(cal),
      opt_(checked(opt, cal)),
      estimator_(cal, opt.height),
      temporal_(opt.temporal),
      tracker_(make_tracker(opt.tracker, opt.ncc, opt.mil)) {}

void StreamEstimator::reset() {
  temporal_.reset();
  tracker_ = make_tracker(opt_.tracker, opt_.ncc, opt_.mil);  // fresh state (MIL counts its seeds)
  index_ = 0;
  seen_box_ = seed_ok_ = tracking_ = false;
  seed_problem_.clear();
  seed_frame_ = gap_ = 0;
  seed_box_ = Box{};
}

std::string StreamEstimator::image_problem(const StreamInput& in, int index, const char* purpose) const {
  const std::string name = frame_name(index);
  const RgbImage* img = in.image;
  if (!img) return name + ": no left image to " + purpose;
  if (img->width != cal_.width || img->height != cal_.height)
    return name + ": left image is " + size_text(img->width, img->height) + " but the frame is " +
           size_text(cal_.width, cal_.height) + " (cannot " + purpose + ")";
  if (img->rgb.size() != static_cast<std::size_t>(img->width) * img->height * 3)
    return name + ": left image of " + size_text(img->width, img->height) + " holds " +
           std::to_string(img->rgb.size()) + " bytes, not width x height x 3 (cannot " + purpose + ")";
  return "";
}

// A frame with a box: keep its gray image for seeding the tracker should a gap
// follow. Seeding waits for the gap, as the batch seeds only then; so does the
// report of a missing or unusable image.
void StreamEstimator::after_box(const StreamInput& in, const Box& box, int index) {
  seen_box_ = true;
  tracking_ = false;
  gap_ = 0;
  seed_frame_ = index;
  seed_box_ = box;
  seed_ok_ = false;
  seed_problem_.clear();
  if (!tracker_) return;
  seed_problem_ = image_problem(in, index, "seed the tracker");
  if (!seed_problem_.empty()) return;
  tracker_->input_channel(*in.image, &seed_gray_);
  seed_ok_ = true;
}

void StreamEstimator::track(const StreamInput& in, StreamFrame* out) {
  if (!tracker_ || !seen_box_) return;  // never before the first box
  ++gap_;
  const std::string name = frame_name(out->index);
  const int limit = opt_.max_track_frames;
  if (limit > 0 && gap_ > limit) {
    if (gap_ == limit + 1)
      out->problems.push_back(name + ": tracking stopped after " + std::to_string(limit) +
                              " frames without a box (max_track_frames)");
    tracking_ = false;
    return;
  }
  if (gap_ == 1) {  // first frame of the gap: seed on the last box frame
    if (!seed_ok_) {
      out->problems.push_back(name + ": cannot track: " + seed_problem_);
      return;
    }
    tracking_ = tracker_->init(view(seed_gray_), seed_box_);
    if (!tracking_)
      out->problems.push_back(name + ": cannot track: the box of " + frame_name(seed_frame_) +
                              " cannot be tracked (too small or no texture)");
  }
  if (!tracking_) return;
  // As in the batch, a frame that cannot be tracked leaves the tracker where it
  // was, and the next frame tries again.
  std::string bad = image_problem(in, out->index, "track the box");
  if (!bad.empty()) {
    out->problems.push_back(bad);
    return;
  }
  tracker_->input_channel(*in.image, &gray_);
  Box b;
  if (tracker_->update(view(gray_), &b)) {
    out->has_box = true;
    out->box = b;
    out->box_source = "tracker";
  } else {
    out->problems.push_back(name + ": tracker lost the box");
  }
}

StreamFrame StreamEstimator::push(const StreamInput& in) {
  StreamFrame out;
  out.index = index_++;
  const std::string name = frame_name(out.index);
  const int W = cal_.width, H = cal_.height;

  for (std::size_t k = 0; k < in.candidates.size(); ++k) {
    const Candidate& c = in.candidates[k];
    if (!c.box.finite() || !std::isfinite(c.score))
      out.problems.push_back(name + ": candidate " + std::to_string(k) +
                             " has a non-finite box or score (ignored)");
  }
  int pick = select_box(in.candidates, W, H, opt_.box_rule);
  if (pick >= 0) {
    out.has_box = true;
    out.box = in.candidates[pick].box;
    out.box_source = "candidates";
    after_box(in, out.box, out.index);
  } else {
    track(in, &out);
  }

  if (out.has_box) {
    const DisparityMap* disp = in.disparity;
    if (!disp) {
      out.problems.push_back(name + ": no disparity map");
    } else {
      std::string mismatch = disparity_mismatch(*disp, W, H, "frame");
      if (!mismatch.empty()) {
        out.problems.push_back(name + ": " + mismatch);
        disp = nullptr;
      }
    }
    out.stage2 = frame_stage2(estimator_, disp, out.box, W, H, name, &out.problems);
  }
  if (out.stage2.has_height) {
    out.has_filtered = true;
    out.filtered = temporal_.add(out.stage2.height);
  }
  out.has_scene_height = temporal_.has_mean();
  out.scene_height = temporal_.mean();
  return out;
}

}  // namespace shle
