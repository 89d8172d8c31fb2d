#include "shle/pipeline.h"

#include <chrono>
#include <cmath>
#include <filesystem>
#include <memory>

#include "shle/disparity_io.h"
#include "shle/error.h"
#include "shle/labelme.h"
#include "shle/released_gate.h"

namespace shle {
namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

std::string describe(const std::exception& e) { return e.what(); }

}  // namespace

DisparityMap load_disparity(const FrameFiles& f, const Calibration& cal, FrameLoader& loader, int width,
                            int height) {
  switch (f.format) {
    case DisparityFormat::Dat:
      return read_dat(f.disparity, width, height, f.fraction_bits);
    case DisparityFormat::Pfm:
      return read_pfm(f.disparity);
    case DisparityFormat::Png16:
      return loader.load_png_disparity(f.disparity, cal.disparity_scale);
    case DisparityFormat::None:
      break;
  }
  throw Error(f.problem.empty() ? f.image + ": no disparity file" : f.problem);
}

void validate(const PipelineOptions& opt) {
  validate(opt.height);
  if (opt.ncc.search_radius < 1 || !(opt.mil.search_radius >= 1))
    throw Error("tracker search radius must be >= 1");
  if (opt.has_gt_height && (!(opt.gt_height > 0) || !std::isfinite(opt.gt_height)))
    throw Error("ground-truth height must be > 0");
  make_tracker(opt.tracker, opt.ncc, opt.mil);  // throws for an unknown kind
}

TemporalFilter::TemporalFilter(const TemporalOptions& o) : opt_(o), kalman_(o.kalman) {
  if (o.use_kalman && o.kalman_compat)
    throw Error("the released Kalman off-by-one (kalman_compat) cannot be computed one frame at a time");
}

double TemporalFilter::add(double raw) {
  const double v = opt_.use_kalman ? kalman_.update(raw) : raw;
  sum_ += v;
  ++count_;
  return v;
}

void TemporalFilter::reset() {
  kalman_ = geometry::ScalarKalman(opt_.kalman);
  sum_ = 0;
  count_ = 0;
}

SceneHeights smooth_heights(const std::vector<double>& raw, const TemporalOptions& o) {
  SceneHeights s;
  s.raw = raw;
  if (o.use_kalman && o.kalman_compat) {
    s.filtered = geometry::kalman_smooth_released(raw, o.kalman);
    if (!s.filtered.empty()) {
      double sum = 0;
      for (double v : s.filtered) sum += v;
      s.scene_height = sum / static_cast<double>(s.filtered.size());
      s.has_scene_height = true;
    }
    return s;
  }
  TemporalFilter f(o);
  s.filtered.reserve(raw.size());
  for (double v : raw) s.filtered.push_back(f.add(v));
  s.has_scene_height = f.has_mean();
  s.scene_height = f.mean();
  return s;
}

std::string disparity_mismatch(const DisparityMap& d, int width, int height, const std::string& frame_what) {
  const std::string size = std::to_string(d.width) + "x" + std::to_string(d.height);
  if (d.width != width || d.height != height)
    return "disparity is " + size + " but the " + frame_what + " is " + std::to_string(width) + "x" +
           std::to_string(height);
  if (d.width < 0 || d.height < 0 || d.d.size() != static_cast<std::size_t>(d.width) * d.height)
    return "disparity map of " + size + " holds " + std::to_string(d.d.size()) + " samples";
  return "";
}

HeightResult frame_stage2(HeightEstimator& estimator, const DisparityMap* disp, const Box& box, int width,
                          int height, const std::string& frame_name, std::vector<std::string>* problems) {
  HeightResult r;
  if (disp) {
    r = estimator.estimate(*disp, box);
    if (!r.has_height) problems->push_back(frame_name + ": no height: " + r.problem);
  } else {
    const HeightOptions& h = estimator.options();
    r.window = extend_and_clip(box, h.extend_top, h.extend_bottom, width, height);
    r.problem = "no disparity";
  }
  return r;
}

SequenceRun run_sequence(const Sequence& seq, const Calibration& cal, BoxSource& source, FrameLoader& loader,
                         const PipelineOptions& opt, const Progress& progress) {
  validate(opt);
  std::unique_ptr<Tracker> tracker = make_tracker(opt.tracker, opt.ncc, opt.mil);
  HeightEstimator estimator(cal, opt.height);
  const Clock::time_point t_start = Clock::now();
  SequenceRun run;
  const std::size_t n = seq.frames.size();
  run.frames.resize(n);
  std::vector<int> width(n, 0), height(n, 0);

  // Pass 1: sizes, true boxes, candidates and the chosen box of every frame.
  for (std::size_t i = 0; i < n; ++i) {
    const FrameFiles& f = seq.frames[i];
    FrameRecord& r = run.frames[i];
    r.index = static_cast<int>(i);
    r.image_name = f.image_name;
    if (!loader.image_size(f.image, &width[i], &height[i])) {
      r.problems.push_back(f.image + ": cannot read the image size; assuming " + std::to_string(cal.width) + "x" +
                           std::to_string(cal.height));
      width[i] = cal.width;
      height[i] = cal.height;
    }
    std::error_code ec;
    if (std::filesystem::exists(f.annotation, ec)) {
      try {
        LabelmeFile lm = load_labelme(f.annotation);
        if (!lm.boxes.empty()) {
          r.has_gt_box = true;
          r.gt_box = lm.boxes.front();
        }
      } catch (const std::exception& e) {
        r.problems.push_back(describe(e));
      }
    }
    std::vector<Candidate> cands;
    try {
      RgbImage img;
      FrameContext ctx{static_cast<int>(i), &f, nullptr};
      if (source.needs_image()) {
        img = loader.load_image(f.image);
        ctx.image = &img;
      }
      cands = source.candidates(ctx);
    } catch (const std::exception& e) {
      // A malformed annotation was already reported above.
      std::string msg = describe(e);
      bool seen = false;
      for (const std::string& p : r.problems) seen = seen || p == msg;
      if (!seen) r.problems.push_back(msg);
    }
    int pick = select_box(cands, width[i], height[i], opt.box_rule);
    if (pick >= 0) {
      r.has_box = true;
      r.box = cands[pick].box;
      r.box_source = source.name();
    }
  }

  // The frames a tracker fills: strictly between two frames with a box.
  std::vector<int> next_box(n + 1, -1);
  for (std::size_t k = n; k-- > 0;) next_box[k] = run.frames[k].has_box ? static_cast<int>(k) : next_box[k + 1];

  // Pass 2: tracking through gaps, disparity, stage 2.
  bool tracking = false;
  for (std::size_t i = 0; i < n; ++i) {
    const FrameFiles& f = seq.frames[i];
    FrameRecord& r = run.frames[i];
    if (r.has_box) {
      tracking = false;
      int after = i + 1 < n ? next_box[i + 1] : -1;
      if (tracker && after > static_cast<int>(i) + 1) {
        Clock::time_point t0 = Clock::now();
        try {
          GrayImage g;
          tracker->input_channel(loader.load_image(f.image), &g);
          tracking = tracker->init(view(g), r.box);
          if (!tracking) r.problems.push_back(f.image + ": the box cannot be tracked (too small or no texture)");
        } catch (const std::exception& e) {
          r.problems.push_back(describe(e) + " (cannot seed the tracker)");
        }
        r.ms_track = ms_since(t0);
      }
    } else if (tracking) {
      Clock::time_point t0 = Clock::now();
      try {
        GrayImage g;
        tracker->input_channel(loader.load_image(f.image), &g);
        Box b;
        if (tracker->update(view(g), &b)) {
          r.has_box = true;
          r.box = b;
          r.box_source = "tracker";
          ++run.frames_tracked;
        } else {
          r.problems.push_back(f.image + ": tracker lost the box");
        }
      } catch (const std::exception& e) {
        r.problems.push_back(describe(e) + " (cannot track)");
      }
      r.ms_track = ms_since(t0);
      if (i + 1 < n && run.frames[i + 1].has_box) tracking = false;
    }

    if (r.has_box) ++run.frames_with_box;
    if (r.has_box && opt.gate_with_annotations) {
      if (!r.has_gt_box)
        r.problems.push_back(f.image_name + ": gated out: no annotation box to gate against (--gate-with-annotations)");
      else if (!released_gate(r.box, r.gt_box))
        r.problems.push_back(f.image_name + ": gated out: the box does not hit the annotation box (--gate-with-annotations)");
      r.gated_out = !r.has_gt_box || !released_gate(r.box, r.gt_box);
      if (r.gated_out) {
        ++run.frames_gated_out;
        const HeightOptions& h = opt.height;
        r.stage2.window = extend_and_clip(r.box, h.extend_top, h.extend_bottom, width[i], height[i]);
        r.stage2.problem = "gated out";
      }
    }
    if (r.has_box && !r.gated_out) {
      Clock::time_point t0 = Clock::now();
      DisparityMap disp;
      bool have_disp = false;
      try {
        disp = load_disparity(f, cal, loader, width[i], height[i]);
        have_disp = true;
      } catch (const std::exception& e) {
        r.problems.push_back(describe(e));
      }
      r.ms_load = ms_since(t0);
      if (have_disp) {
        std::string mismatch = disparity_mismatch(disp, width[i], height[i], "image");
        if (!mismatch.empty()) {
          r.problems.push_back(f.disparity + ": " + mismatch);
          have_disp = false;
        }
      }
      Clock::time_point t1 = Clock::now();
      r.stage2 = frame_stage2(estimator, have_disp ? &disp : nullptr, r.box, width[i], height[i], f.image_name,
                              &r.problems);
      if (have_disp) r.ms_stage2 = ms_since(t1);
    }
    if (progress) progress(i + 1, n);
  }

  // Temporal filter over the frames that have a height.
  std::vector<double> raw;
  for (const FrameRecord& r : run.frames)
    if (r.stage2.has_height) raw.push_back(r.stage2.height);
  run.heights = smooth_heights(raw, opt.temporal);
  run.frames_used = raw.size();
  std::size_t k = 0;
  for (FrameRecord& r : run.frames)
    if (r.stage2.has_height) {
      r.has_filtered = true;
      r.filtered = run.heights.filtered[k++];
    }

  if (opt.has_gt_height && run.heights.has_scene_height) {
    run.has_errors = true;
    run.scene_error = height_error(run.heights.scene_height, opt.gt_height);
    run.filtered_errors = summarize_height_errors(run.heights.filtered, opt.gt_height);
    run.raw_errors = summarize_height_errors(run.heights.raw, opt.gt_height);
  }
  for (const FrameRecord& r : run.frames) {
    CentreDistance c;
    if (r.has_box && r.has_gt_box && centre_distance(r.box, r.gt_box, &c)) {
      ++run.box_metric_frames;
      run.box_metrics.cpd += c.cpd;
      run.box_metrics.rcpda += c.rcpda;
      run.box_metrics.rcpdh += c.rcpdh;
    }
  }
  if (run.box_metric_frames) {
    double s = 1.0 / static_cast<double>(run.box_metric_frames);
    run.box_metrics.cpd *= s;
    run.box_metrics.rcpda *= s;
    run.box_metrics.rcpdh *= s;
  }
  run.ms_total = ms_since(t_start);
  return run;
}

}  // namespace shle
