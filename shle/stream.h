// SHLE one frame at a time, for embedders that receive frames as they come
// (run_sequence in pipeline.h is the batch over a sequence folder). Per pushed
// frame: a box is chosen among the caller's candidates with the box rule
// (select_box); a frame without one is tracked forward from the last box;
// stage 2 runs on the box; the temporal filter and the scene height (mean of
// the filtered heights so far) are updated.
//
// Same results as run_sequence, frame for frame, when the frames, candidates
// and images are the same and the images are the calibration's size, with
// these differences:
//  - Tracking (the one difference in what is computed). The batch fills only
//    the frames strictly between two frames with a box: it knows the future. A
//    stream cannot know whether another box will come, so it tracks every frame
//    without a box after a box, for at most options.max_track_frames frames
//    (0 = no limit). Frames after the last box of a scene may therefore get a
//    tracked box and a height here where the batch has none, and a gap longer
//    than max_track_frames between two boxes is tracked only for its first
//    max_track_frames frames (the batch tracks all of it). Frames before the
//    first box are never tracked, as in the batch. Within those limits a gap
//    between two boxes gets the batch's results: the tracker is seeded lazily,
//    on the first frame of a gap, with the gray image and box of the frame
//    before it, so it is seeded once per gap as in the batch (which matters for
//    the MIL tracker, whose random features depend on the number of seeds).
//    To make this possible the gray image of the last frame with a box is kept,
//    so with a tracker configured every frame with a box needs its image too.
//  - kalman_compat (the released off-by-one: value i is the estimate after
//    measurement i + 1, and the last value is 0) is refused: the constructor
//    throws shle::Error when use_kalman and kalman_compat are both set.
//  - The frame size is the calibration's width x height (the batch reads it
//    from each image file): the disparity map, and the image when one is used,
//    must be that size.
//  - Problem messages name "frame <index>" instead of files, and a tracker that
//    cannot be seeded is reported on the first frame of the gap, not on the
//    frame with the box.
//
// A bad frame never throws: its problems are recorded in StreamFrame::problems
// and it gets no height (a frame without a usable disparity map still gets its
// box, and can seed the tracker, as in the batch). Not thread-safe: one
// estimator per stream.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "shle/calibration.h"
#include "shle/height.h"
#include "shle/pipeline.h"
#include "shle/tracker.h"
#include "shle/types.h"

namespace shle {

struct StreamInput {
  // Required; must be calibration.width x calibration.height. Null: the frame
  // is reported as having no disparity (its box is still chosen and tracked).
  const DisparityMap* disparity = nullptr;
  // The box source's output for this frame (a detector's, or the caller's);
  // empty when there is none. Candidates with a non-finite box or score are
  // reported and ignored.
  std::vector<Candidate> candidates;
  // The left image, calibration.width x calibration.height. Used only with a
  // tracker: to seed it on a frame with a box and to track a frame without one.
  // Only read during push(); it need not outlive the call.
  const RgbImage* image = nullptr;
};

struct StreamFrame {
  int index = 0;             // frames pushed since construction or reset(), from 0
  bool has_box = false;
  Box box;                   // chosen or tracked box, before extension
  std::string box_source;    // "candidates", "tracker", or "" without a box
  HeightResult stage2;       // stage2.window: the box after extension and clipping
  bool has_filtered = false; // this frame has a height (stage2.has_height)
  double filtered = 0;       // its filtered height
  bool has_scene_height = false;
  double scene_height = 0;   // mean of the filtered heights of the scene so far
  std::vector<std::string> problems;  // one line each
};

class StreamEstimator {
 public:
  // Throws shle::Error for options run_sequence refuses (validate() in
  // pipeline.h), for kalman_compat with use_kalman, for max_track_frames < 0,
  // and for a calibration without a positive width and height.
  StreamEstimator(const Calibration& calibration, const PipelineOptions& options);

  StreamFrame push(const StreamInput& input);
  // Starts a new scene: frame indices, tracker, Kalman filter and scene mean
  // start over, as in a newly constructed estimator.
  void reset();

  int frames() const { return index_; }                  // pushed since the last reset
  std::size_t frames_used() const { return temporal_.count(); }  // with a height
  bool has_scene_height() const { return temporal_.has_mean(); }
  double scene_height() const { return temporal_.mean(); }
  const PipelineOptions& options() const { return opt_; }

 private:
  // "" when in.image can be used, else the problem (naming frame `index`).
  std::string image_problem(const StreamInput& in, int index, const char* purpose) const;
  void after_box(const StreamInput& in, const Box& box, int index);
  void track(const StreamInput& in, StreamFrame* out);

  Calibration cal_;
  PipelineOptions opt_;
  HeightEstimator estimator_;
  TemporalFilter temporal_;
  std::unique_ptr<Tracker> tracker_;  // null with tracker "none"
  int index_ = 0;
  // Tracking state since the last frame with a box.
  bool seen_box_ = false;     // a box since the last reset
  bool seed_ok_ = false;      // seed_gray_ / seed_box_ hold the last box frame
  std::string seed_problem_;  // why not, when !seed_ok_
  int seed_frame_ = 0;
  Box seed_box_;
  GrayImage seed_gray_, gray_;
  int gap_ = 0;               // frames without a box since the last box
  bool tracking_ = false;     // seeded for this gap
};

}  // namespace shle
