// A whole sequence through SHLE: boxes per frame (box source + box rule), gaps
// between boxes filled by a tracker, stage 2 per frame, then the Kalman filter
// over the frames that have a height and the scene height (mean of the filtered
// heights). Image files are decoded by the caller's FrameLoader: the library
// itself never touches image formats.
#pragma once

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "geometry/kalman.h"
#include "shle/box_rules.h"
#include "shle/box_source.h"
#include "shle/calibration.h"
#include "shle/dataset.h"
#include "shle/height.h"
#include "shle/metrics.h"
#include "shle/tracker.h"

namespace shle {

struct TemporalOptions {
  geometry::KalmanOptions kalman;
  bool use_kalman = true;      // false: filtered = raw (Table III "- Kalman")
  bool kalman_compat = false;  // the released off-by-one (kalman.h)
};

struct PipelineOptions {
  HeightOptions height;
  TemporalOptions temporal;
  BoxRuleOptions box_rule;
  std::string tracker = "ncc";  // "ncc", "mil" or "none"
  NccOptions ncc;
  MilOptions mil;
  // StreamEstimator only (shle/stream.h): frames without a box tracked after the
  // last box, 0 = no limit. run_sequence ignores it: it tracks only through gaps
  // between two boxes, however long.
  int max_track_frames = 30;
  // The released stage-2 frame gate (shle/released_gate.h): a frame whose box
  // does not hit its LabelMe annotation box, or that has none, gets no height.
  // Uses the ground truth; off by default. run_sequence only (StreamEstimator
  // has no annotations and refuses it).
  bool gate_with_annotations = false;
  bool has_gt_height = false;
  double gt_height = 0;
};

// The checks run_sequence and StreamEstimator make: stage-2 options, tracker
// kind and search radius, ground-truth height. Throws shle::Error.
void validate(const PipelineOptions& options);

class FrameLoader {
 public:
  virtual ~FrameLoader() = default;
  // The decoded left image as 8-bit RGB; throws with a message naming the file.
  virtual RgbImage load_image(const std::string& path) = 0;
  // Image size from the file header alone; false when it cannot be read.
  virtual bool image_size(const std::string& path, int* width, int* height) = 0;
  // A 16-bit PNG disparity, every sample divided by `scale`; throws on failure.
  virtual DisparityMap load_png_disparity(const std::string& path, double scale) = 0;
};

// Reads a frame's disparity in its format; a headerless .dat is read as
// width x height. Throws shle::Error.
DisparityMap load_disparity(const FrameFiles& frame, const Calibration& calibration,
                            FrameLoader& loader, int width, int height);

struct FrameRecord {
  int index = 0;
  std::string image_name;
  std::string box_source;  // the source's name, "tracker", or "" without a box
  bool has_box = false;
  bool gated_out = false;  // has a box, refused by gate_with_annotations
  Box box;                 // chosen or tracked box, before extension
  HeightResult stage2;     // stage2.window: the box after extension and clipping
  bool has_filtered = false;
  double filtered = 0;
  bool has_gt_box = false;
  Box gt_box;              // first "height" rectangle of the frame's LabelMe file
  std::vector<std::string> problems;
  double ms_load = 0, ms_track = 0, ms_stage2 = 0;
};

struct SceneHeights {
  std::vector<double> raw, filtered;  // over the frames with a height, in order
  bool has_scene_height = false;
  double scene_height = 0;            // mean of `filtered`
};

// The temporal stage alone: Kalman (or not) over the raw heights.
SceneHeights smooth_heights(const std::vector<double>& raw, const TemporalOptions& options);

// The temporal stage one raw height at a time, as smooth_heights computes it
// (same operations in the same order, so the same bits): the filtered height
// (Kalman, or the raw height with use_kalman = false) and the scene height so
// far, the mean of the filtered heights. The kalman_compat mode cannot run this
// way (its value i is the estimate after measurement i + 1, and its last value
// is 0): the constructor throws shle::Error for it.
class TemporalFilter {
 public:
  explicit TemporalFilter(const TemporalOptions& options);
  double add(double raw);  // returns the filtered height
  void reset();
  std::size_t count() const { return count_; }
  bool has_mean() const { return count_ > 0; }
  double mean() const { return count_ ? sum_ / static_cast<double>(count_) : 0.0; }

 private:
  TemporalOptions opt_;
  geometry::ScalarKalman kalman_;
  double sum_ = 0;
  std::size_t count_ = 0;
};

// Stage 2 on one frame with a box, as run_sequence and StreamEstimator run it.
// `disparity` is null when the frame has no usable map (the reason is already
// in `problems`): the result then has no height, problem "no disparity", and
// the window of the box extended and clipped to width x height. Otherwise
// `disparity` must be width x height (see disparity_mismatch). A frame without
// a height adds "<frame_name>: no height: <reason>" to `problems`.
HeightResult frame_stage2(HeightEstimator& estimator, const DisparityMap* disparity, const Box& box, int width,
                          int height, const std::string& frame_name, std::vector<std::string>* problems);

// "" when `disparity` is width x height and holds that many samples; otherwise
// "disparity is WxH but the <frame_what> is WxH" (or, for a map whose buffer
// does not match its size, "disparity map of WxH holds N samples").
std::string disparity_mismatch(const DisparityMap& disparity, int width, int height, const std::string& frame_what);

struct SequenceRun {
  std::vector<FrameRecord> frames;
  std::size_t frames_with_box = 0, frames_tracked = 0, frames_used = 0, frames_gated_out = 0;
  SceneHeights heights;
  bool has_errors = false;  // with a ground-truth height
  HeightError scene_error;
  HeightErrorSummary filtered_errors, raw_errors;
  std::size_t box_metric_frames = 0;  // frames with a box and a LabelMe box
  CentreDistance box_metrics;         // means over those frames
  double ms_total = 0;
};

using Progress = std::function<void(std::size_t done, std::size_t total)>;

// Never throws for a bad frame: its problems are recorded and it gets no height.
// Throws shle::Error only for bad options.
SequenceRun run_sequence(const Sequence& sequence, const Calibration& calibration, BoxSource& boxes,
                         FrameLoader& loader, const PipelineOptions& options,
                         const Progress& progress = {});

}  // namespace shle
