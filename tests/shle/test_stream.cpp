// StreamEstimator against run_sequence on the same synthetic frames, held in
// memory: the batch reads them through an in-memory FrameLoader and BoxSource,
// the stream gets them pushed one by one. Then the stream-only behaviour
// (tracking after the last box, max_track_frames), bad input and reset().
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "shle/error.h"
#include "shle/metrics.h"
#include "shle/pipeline.h"
#include "shle/stream.h"
#include "shle/synth.h"
#include "tests/shle/test_util.h"

namespace {

// 640x360 drive towards a bar, every frame with a simulated detection and its
// distractors (left, low, top edge) for the paper box rule to reject.
struct Scene {
  shle::Calibration cal;
  std::vector<shle::synth::Frame> frames;
  std::vector<shle::DisparityMap> disp;
};

const Scene& scene() {
  static const Scene s = [] {
    shle::synth::SceneSpec spec;
    spec.seed = 41;
    spec.frames = 14;
    spec.start_distance = 40;
    spec.end_distance = 22;
    spec.width = 640;
    spec.height = 360;
    spec.fx = spec.fy = 1000;
    spec.cx = 320;
    spec.cy = 180;
    spec.miss_rate = 0;
    shle::synth::Scene sc(spec);
    Scene out;
    out.cal = sc.calibration();
    for (int k = 0; k < sc.frame_count(); ++k) {
      out.frames.push_back(sc.render(k));
      const shle::synth::Frame& f = out.frames.back();
      shle::DisparityMap d;
      d.width = f.image.width;
      d.height = f.image.height;
      d.d.resize(f.disparity.size());
      for (std::size_t i = 0; i < d.d.size(); ++i) d.d[i] = f.disparity[i] / 32.0f;
      out.disp.push_back(std::move(d));
    }
    return out;
  }();
  return s;
}

// The candidates of frame k, none for the frames in `no_box`.
std::vector<shle::Candidate> candidates(int k, const std::set<int>& no_box) {
  if (no_box.count(k)) return {};
  return scene().frames[k].detections;
}

// Frame k's files are "image/k" and "disparity/k"; the loader and box source
// serve them from memory.
class MemoryLoader : public shle::FrameLoader {
 public:
  shle::RgbImage load_image(const std::string& path) override { return scene().frames[index(path)].image; }
  bool image_size(const std::string& path, int* width, int* height) override {
    const shle::RgbImage& img = scene().frames[index(path)].image;
    *width = img.width;
    *height = img.height;
    return true;
  }
  shle::DisparityMap load_png_disparity(const std::string& path, double) override {
    return scene().disp[index(path)];
  }

 private:
  static int index(const std::string& path) { return std::stoi(path.substr(path.find('/') + 1)); }
};

class MemoryBoxes : public shle::BoxSource {
 public:
  explicit MemoryBoxes(std::set<int> no_box) : no_box_(std::move(no_box)) {}
  std::string name() const override { return "candidates"; }
  std::vector<shle::Candidate> candidates(const shle::FrameContext& frame) override {
    return ::candidates(frame.index, no_box_);
  }

 private:
  std::set<int> no_box_;
};

shle::SequenceRun batch(const shle::PipelineOptions& opt, const std::set<int>& no_box = {}) {
  shle::Sequence seq;
  for (std::size_t k = 0; k < scene().frames.size(); ++k) {
    shle::FrameFiles f;
    f.image_name = f.stem = std::to_string(k);
    f.image = "image/" + std::to_string(k);
    f.disparity = "disparity/" + std::to_string(k);
    f.format = shle::DisparityFormat::Png16;
    seq.frames.push_back(f);
  }
  MemoryLoader loader;
  MemoryBoxes boxes(no_box);
  return shle::run_sequence(seq, scene().cal, boxes, loader, opt);
}

std::vector<shle::StreamFrame> stream(shle::StreamEstimator& est, const std::set<int>& no_box = {}) {
  std::vector<shle::StreamFrame> out;
  for (std::size_t k = 0; k < scene().frames.size(); ++k) {
    shle::StreamInput in;
    in.disparity = &scene().disp[k];
    in.candidates = candidates(static_cast<int>(k), no_box);
    in.image = &scene().frames[k].image;
    out.push_back(est.push(in));
  }
  return out;
}

std::vector<shle::StreamFrame> stream(const shle::PipelineOptions& opt, const std::set<int>& no_box = {}) {
  shle::StreamEstimator est(scene().cal, opt);
  return stream(est, no_box);
}

void expect_same_box(const shle::Box& a, const shle::Box& b, const std::string& where) {
  EXPECT_EQ(a.x0, b.x0) << where;
  EXPECT_EQ(a.y0, b.y0) << where;
  EXPECT_EQ(a.x1, b.x1) << where;
  EXPECT_EQ(a.y1, b.y1) << where;
}

// Frame k of the stream equals frame k of the batch: box, stage 2, filtered
// height, and the scene height so far (the running mean of the batch's
// filtered heights up to k, summed in the same order).
void expect_same_frame(const shle::StreamFrame& s, const shle::FrameRecord& b, double batch_scene_so_far,
                       bool batch_has_scene) {
  const std::string where = "frame " + std::to_string(b.index);
  EXPECT_EQ(s.index, b.index);
  ASSERT_EQ(s.has_box, b.has_box) << where;
  EXPECT_EQ(s.box_source, b.box_source) << where;
  expect_same_box(s.box, b.box, where);
  expect_same_box(s.stage2.window, b.stage2.window, where);
  ASSERT_EQ(s.stage2.has_height, b.stage2.has_height) << where;
  EXPECT_EQ(s.stage2.height, b.stage2.height) << where;
  EXPECT_EQ(s.stage2.points, b.stage2.points) << where;
  ASSERT_EQ(s.has_filtered, b.has_filtered) << where;
  EXPECT_EQ(s.filtered, b.filtered) << where;
  ASSERT_EQ(s.has_scene_height, batch_has_scene) << where;
  EXPECT_EQ(s.scene_height, batch_scene_so_far) << where;
}

// Compares frames [0, end) and returns how many had a height.
std::size_t expect_same_frames(const std::vector<shle::StreamFrame>& s, const shle::SequenceRun& b,
                               std::size_t end) {
  double sum = 0;
  std::size_t n = 0;
  for (std::size_t k = 0; k < end; ++k) {
    if (b.frames[k].has_filtered) {
      sum += b.frames[k].filtered;
      ++n;
    }
    expect_same_frame(s[k], b.frames[k], n ? sum / static_cast<double>(n) : 0.0, n > 0);
  }
  return n;
}

bool has_problem(const shle::StreamFrame& f, const std::string& text) {
  for (const std::string& p : f.problems)
    if (p.find(text) != std::string::npos) return true;
  return false;
}

std::string problems(const shle::StreamFrame& f) {
  std::string all;
  for (const std::string& p : f.problems) all += p + "\n";
  return all;
}

TEST(Stream, EveryFrameWithABoxEqualsBatch) {
  const std::size_t n = scene().frames.size();
  for (bool use_kalman : {true, false}) {
    SCOPED_TRACE(use_kalman ? "kalman" : "no kalman");
    shle::PipelineOptions opt;
    opt.temporal.use_kalman = use_kalman;
    shle::SequenceRun b = batch(opt);
    ASSERT_EQ(b.frames_with_box, n);
    ASSERT_EQ(b.frames_used, n);
    ASSERT_EQ(b.frames_tracked, 0u);
    std::vector<shle::StreamFrame> s = stream(opt);
    ASSERT_EQ(s.size(), n);
    EXPECT_EQ(expect_same_frames(s, b, n), n);
    EXPECT_EQ(s.back().scene_height, b.heights.scene_height);
    ASSERT_TRUE(b.heights.has_scene_height);
    // The paper rule picked the detection, not a distractor; no frame had a problem.
    for (std::size_t k = 0; k < n; ++k) {
      EXPECT_EQ(s[k].box_source, "candidates");
      EXPECT_TRUE(s[k].problems.empty()) << problems(s[k]);
      shle::CentreDistance c;
      ASSERT_TRUE(shle::centre_distance(s[k].box, scene().frames[k].box, &c));
      EXPECT_LT(c.cpd, 30.0) << k;  // the detections are jittered
      EXPECT_NEAR(s[k].stage2.height, 3.3, 1.0) << k;
    }
    // The Kalman filter did something (or, without it, nothing).
    std::size_t differ = 0;
    for (const shle::StreamFrame& f : s) differ += f.filtered != f.stage2.height;
    if (use_kalman)
      EXPECT_GE(differ, n - 1);  // all but the first, which seeds the state
    else
      EXPECT_EQ(differ, 0u);
  }
}

TEST(Stream, GapsBetweenBoxesEqualBatch) {
  const int n = static_cast<int>(scene().frames.size());
  const int last = n - 1;
  // Frame 0 before the first box, gaps 3-4 and 7-9, the last frame after the last box.
  const std::set<int> no_box = {0, 3, 4, 7, 8, 9, last};
  for (const char* tracker : {"ncc", "mil"}) {
    SCOPED_TRACE(tracker);
    shle::PipelineOptions opt;
    opt.tracker = tracker;
    shle::SequenceRun b = batch(opt, no_box);
    std::vector<shle::StreamFrame> s = stream(opt, no_box);
    ASSERT_EQ(b.frames_tracked, 5u);
    for (int k : {3, 4, 7, 8, 9}) {
      EXPECT_EQ(b.frames[k].box_source, "tracker") << k;
      EXPECT_TRUE(b.frames[k].stage2.has_height) << k;
    }
    EXPECT_EQ(expect_same_frames(s, b, last), static_cast<std::size_t>(last - 1));
    EXPECT_FALSE(s[0].has_box);
    EXPECT_TRUE(s[0].problems.empty()) << problems(s[0]);
    // After the last box the batch stops; the stream tracks on (the documented difference).
    EXPECT_FALSE(b.frames[last].has_box);
    EXPECT_TRUE(s[last].has_box);
    EXPECT_EQ(s[last].box_source, "tracker");
    EXPECT_EQ(s[last].box.width(), std::trunc(s[last - 1].box.width()));
  }
  // Without a tracker the gaps stay empty, as in the batch.
  shle::PipelineOptions none;
  none.tracker = "none";
  shle::SequenceRun b = batch(none, no_box);
  std::vector<shle::StreamFrame> s = stream(none, no_box);
  EXPECT_EQ(expect_same_frames(s, b, n), static_cast<std::size_t>(n) - no_box.size());
  EXPECT_EQ(s.back().scene_height, b.heights.scene_height);
  EXPECT_FALSE(s[3].has_box);
}

TEST(Stream, TrackingStopsAfterMaxTrackFrames) {
  const int n = static_cast<int>(scene().frames.size());
  std::set<int> no_box;
  for (int k = 1; k < n; ++k)
    if (k != 8) no_box.insert(k);  // boxes on frames 0 and 8 only
  shle::PipelineOptions opt;
  opt.max_track_frames = 3;
  std::vector<shle::StreamFrame> s = stream(opt, no_box);
  for (int k = 1; k <= 3; ++k) {
    EXPECT_EQ(s[k].box_source, "tracker") << k;
    EXPECT_TRUE(s[k].stage2.has_height) << k;
  }
  EXPECT_FALSE(s[4].has_box);
  EXPECT_TRUE(has_problem(s[4], "frame 4: tracking stopped after 3 frames without a box")) << problems(s[4]);
  for (int k = 5; k <= 7; ++k) {
    EXPECT_FALSE(s[k].has_box) << k;
    EXPECT_TRUE(s[k].problems.empty()) << problems(s[k]);
  }
  EXPECT_EQ(s[8].box_source, "candidates");  // a new box: tracking starts over
  for (int k = 9; k <= 11; ++k) EXPECT_EQ(s[k].box_source, "tracker") << k;
  EXPECT_FALSE(s[12].has_box);
  EXPECT_TRUE(s[4].has_scene_height);  // frames 0-3 had heights
  EXPECT_EQ(s[7].scene_height, s[3].scene_height);

  opt.max_track_frames = 0;  // no limit
  s = stream(opt, no_box);
  for (int k = 1; k < n; ++k) EXPECT_TRUE(s[k].has_box) << k;
  opt.max_track_frames = 1;
  s = stream(opt, no_box);
  EXPECT_EQ(s[1].box_source, "tracker");
  EXPECT_FALSE(s[2].has_box);
}

TEST(Stream, BadInputIsReportedNotFatal) {
  const Scene& sc = scene();
  shle::StreamEstimator est(sc.cal, {});
  auto input = [&](int k) {
    shle::StreamInput in;
    in.disparity = &sc.disp[k];
    in.candidates = sc.frames[k].detections;
    in.image = &sc.frames[k].image;
    return in;
  };

  // 0: disparity of the wrong size; the box is still chosen.
  shle::DisparityMap small;
  small.width = small.height = 10;
  small.d.assign(100, 5.0f);
  shle::StreamInput in = input(0);
  in.disparity = &small;
  shle::StreamFrame f = est.push(in);
  EXPECT_TRUE(f.has_box);
  EXPECT_FALSE(f.stage2.has_height);
  EXPECT_EQ(f.stage2.problem, "no disparity");
  EXPECT_TRUE(has_problem(f, "frame 0: disparity is 10x10 but the frame is 640x360")) << problems(f);
  EXPECT_FALSE(f.has_scene_height);

  // 1: right size, buffer too short.
  shle::DisparityMap shorter = sc.disp[1];
  shorter.d.resize(shorter.d.size() / 2);
  in = input(1);
  in.disparity = &shorter;
  f = est.push(in);
  EXPECT_FALSE(f.stage2.has_height);
  EXPECT_TRUE(has_problem(f, "frame 1: disparity map of 640x360 holds 115200 samples")) << problems(f);

  // 2: no disparity at all.
  in = input(2);
  in.disparity = nullptr;
  f = est.push(in);
  EXPECT_TRUE(f.has_box);
  EXPECT_FALSE(f.stage2.has_height);
  EXPECT_TRUE(has_problem(f, "frame 2: no disparity map")) << problems(f);

  // 3: a NaN box beside the detection is ignored; 4: a lone NaN box gives no box.
  const double nan = std::numeric_limits<double>::quiet_NaN();
  in = input(3);
  in.candidates.insert(in.candidates.begin(), shle::Candidate{shle::Box{nan, 10, 200, 100}, 0.99});
  f = est.push(in);
  EXPECT_TRUE(has_problem(f, "frame 3: candidate 0 has a non-finite box or score (ignored)")) << problems(f);
  ASSERT_TRUE(f.stage2.has_height) << problems(f);
  EXPECT_TRUE(f.has_scene_height);
  expect_same_box(f.box, sc.frames[3].detections.front().box, "frame 3");

  in = input(4);
  in.candidates = {shle::Candidate{shle::Box{100, nan, 200, 150}, 0.9}};
  in.image = nullptr;  // and no image to track with
  f = est.push(in);
  EXPECT_FALSE(f.has_box);
  EXPECT_TRUE(has_problem(f, "non-finite")) << problems(f);
  EXPECT_TRUE(has_problem(f, "frame 4: no left image to track the box")) << problems(f);

  // 5: an image of the wrong size, 6: an image whose buffer is short.
  shle::RgbImage tiny;
  tiny.width = tiny.height = 4;
  tiny.rgb.assign(48, 128);
  in = input(5);
  in.candidates.clear();
  in.image = &tiny;
  f = est.push(in);
  EXPECT_FALSE(f.has_box);
  EXPECT_TRUE(has_problem(f, "frame 5: left image is 4x4 but the frame is 640x360")) << problems(f);
  shle::RgbImage cut = sc.frames[6].image;
  cut.rgb.resize(cut.rgb.size() - 1);
  in = input(6);
  in.candidates.clear();
  in.image = &cut;
  f = est.push(in);
  EXPECT_FALSE(f.has_box);
  EXPECT_TRUE(has_problem(f, "holds 691199 bytes")) << problems(f);
  // 7: the image is back: tracking resumes from where the tracker was.
  in = input(7);
  in.candidates.clear();
  f = est.push(in);
  EXPECT_EQ(f.box_source, "tracker") << problems(f);
  const std::size_t tracked_heights = f.stage2.has_height ? 1 : 0;

  // 8: a box frame without an image cannot seed the tracker; 9: reported in the gap.
  in = input(8);
  in.image = nullptr;
  f = est.push(in);
  EXPECT_TRUE(f.stage2.has_height);
  EXPECT_TRUE(f.problems.empty()) << problems(f);
  in = input(9);
  in.candidates.clear();
  f = est.push(in);
  EXPECT_FALSE(f.has_box);
  EXPECT_TRUE(has_problem(f, "frame 9: cannot track: frame 8: no left image to seed the tracker")) << problems(f);
  f = est.push(in);  // reported once per gap
  EXPECT_TRUE(f.problems.empty()) << problems(f);

  // 11: an inverted box and 12: a box far off the map reach stage 2 and are reported.
  in = input(11);
  in.candidates = {shle::Candidate{shle::Box{400, 100, 300, 150}, 0.9}};
  f = est.push(in);
  EXPECT_TRUE(f.has_box);
  EXPECT_TRUE(has_problem(f, "frame 11: no height: box is empty")) << problems(f);
  in = input(12);
  in.candidates = {shle::Candidate{shle::Box{1e300, 100, 2e300, 150}, 0.9}};
  f = est.push(in);
  EXPECT_TRUE(has_problem(f, "box lies outside the 640x360 disparity map")) << problems(f);
  // The estimator still works.
  f = est.push(input(13));
  EXPECT_TRUE(f.stage2.has_height) << problems(f);
  EXPECT_EQ(est.frames(), 14);
  EXPECT_EQ(est.frames_used(), 3 + tracked_heights);  // frames 3, 8, 13 and the tracked 7
  EXPECT_EQ(f.has_scene_height, true);
}

TEST(Stream, BadOptionsThrow) {
  const shle::Calibration& cal = scene().cal;
  auto make = [](const shle::Calibration& c, const shle::PipelineOptions& o) { shle::StreamEstimator e(c, o); };
  shle::PipelineOptions opt;
  opt.temporal.kalman_compat = true;
  EXPECT_THROW_MSG(make(cal, opt), "kalman_compat");
  opt.temporal.use_kalman = false;  // compat has no effect without the filter
  EXPECT_NO_THROW(make(cal, opt));
  opt = {};
  opt.max_track_frames = -1;
  EXPECT_THROW_MSG(make(cal, opt), "max_track_frames must be >= 0");
  opt = {};
  opt.tracker = "kcf";
  EXPECT_THROW_MSG(make(cal, opt), "unknown tracker 'kcf'");
  opt = {};
  opt.ncc.search_radius = 0;
  EXPECT_THROW_MSG(make(cal, opt), "search radius");
  opt = {};
  opt.height.sigma = -1;
  EXPECT_THROW(make(cal, opt), shle::Error);
  shle::Calibration no_size = cal;
  no_size.width = 0;
  EXPECT_THROW_MSG(make(no_size, shle::PipelineOptions{}), "calibration width and height must be > 0");
}

TEST(Stream, ResetEqualsFreshEstimator) {
  const std::set<int> no_box = {2, 3, 6, 7, 12, 13};
  for (const char* tracker : {"ncc", "mil"}) {
    SCOPED_TRACE(tracker);
    shle::PipelineOptions opt;
    opt.tracker = tracker;
    shle::StreamEstimator used(scene().cal, opt);
    // A different scene first: other gaps, so the tracker and the filter hold other state.
    std::vector<shle::StreamFrame> first = stream(used, {0, 4, 5, 9, 10, 11});
    ASSERT_TRUE(first.back().has_scene_height);
    used.reset();
    EXPECT_EQ(used.frames(), 0);
    EXPECT_FALSE(used.has_scene_height());
    std::vector<shle::StreamFrame> again = stream(used, no_box);
    std::vector<shle::StreamFrame> fresh = stream(opt, no_box);
    ASSERT_EQ(again.size(), fresh.size());
    for (std::size_t k = 0; k < fresh.size(); ++k) {
      const std::string where = "frame " + std::to_string(k);
      EXPECT_EQ(again[k].index, fresh[k].index);
      EXPECT_EQ(again[k].has_box, fresh[k].has_box) << where;
      EXPECT_EQ(again[k].box_source, fresh[k].box_source) << where;
      expect_same_box(again[k].box, fresh[k].box, where);
      EXPECT_EQ(again[k].stage2.height, fresh[k].stage2.height) << where;
      EXPECT_EQ(again[k].filtered, fresh[k].filtered) << where;
      EXPECT_EQ(again[k].scene_height, fresh[k].scene_height) << where;
      EXPECT_EQ(again[k].problems, fresh[k].problems) << where;
    }
    EXPECT_EQ(fresh[12].box_source, "tracker");
    EXPECT_EQ(used.scene_height(), fresh.back().scene_height);
    EXPECT_NE(first.back().scene_height, fresh.back().scene_height);
  }
}

}  // namespace
