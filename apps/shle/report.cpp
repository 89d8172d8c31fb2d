#include "apps/shle/report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "weights/json.h"

namespace shleapp {
namespace {

std::string num(double v, const char* f = "%.6f") {
  if (!std::isfinite(v)) return "";
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

// JSON number, or null for a non-finite value.
std::string jnum(double v) {
  if (!std::isfinite(v)) return "null";
  char b[64];
  std::snprintf(b, sizeof b, "%.10g", v);
  return b;
}

std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

}  // namespace

std::string frames_csv(const shle::SequenceRun& run) {
  std::string s = "frame,image,box_source,x0,y0,x1,y1,points,height_raw,height_filtered\n";
  for (const shle::FrameRecord& r : run.frames) {
    s += std::to_string(r.index) + "," + csv_field(r.image_name) + "," + r.box_source + ",";
    if (r.has_box) {
      const shle::Box& w = r.stage2.window;
      s += num(w.x0, "%.3f") + "," + num(w.y0, "%.3f") + "," + num(w.x1, "%.3f") + "," + num(w.y1, "%.3f") + "," +
           std::to_string(r.stage2.window_points) + ",";
    } else {
      s += ",,,,,";
    }
    // %.17g: the doubles round-trip exactly (reference comparisons read them back).
    s += (r.stage2.has_height ? num(r.stage2.height, "%.17g") : "") + ",";
    s += (r.has_filtered ? num(r.filtered, "%.17g") : "") + "\n";
  }
  return s;
}

std::string summary_json(const shle::SequenceRun& run, const RunDescription& d) {
  const shle::PipelineOptions& o = d.options;
  std::string s = "{\n";
  auto kv = [&](const std::string& k, const std::string& v, bool last = false) {
    s += "  " + json::quote(k) + ": " + v + (last ? "\n" : ",\n");
  };
  kv("sequence", json::quote(d.sequence));
  kv("layout", json::quote(d.layout));
  kv("calibration", json::quote(d.calibration));
  kv("box_source", json::quote(d.box_source));
  if (d.box_source == "detector") {
    std::string labels;
    for (int l : d.detector.labels) labels += (labels.empty() ? "" : ", ") + std::to_string(l);
    kv("detector", "{\"model\": " + json::quote(d.detector.model) + ", \"weights\": " +
                       json::quote(d.detector.weights) + ", \"classes\": " + std::to_string(d.detector.classes) +
                       ", \"labels\": [" + labels + "], \"score_threshold\": " + jnum(d.detector.score_threshold) +
                       "}");
  }
  if (!d.box_path.empty()) kv("box_path", json::quote(d.box_path));
  if (!d.coco_images.empty()) kv("coco_images", json::quote(d.coco_images));
  kv("box_rule", json::quote(d.box_rule));
  kv("tracker", json::quote(d.tracker));
  kv("frames", std::to_string(run.frames.size()));
  kv("frames_with_box", std::to_string(run.frames_with_box));
  kv("frames_tracked", std::to_string(run.frames_tracked));
  kv("frames_used", std::to_string(run.frames_used));
  kv("frames_gated_out", std::to_string(run.frames_gated_out));
  kv("scene_height", run.heights.has_scene_height ? jnum(run.heights.scene_height) : "null");
  kv("gt_height", o.has_gt_height ? jnum(o.gt_height) : "null");
  if (run.has_errors) {
    kv("he", jnum(run.scene_error.he));
    kv("her", jnum(run.scene_error.her));
    kv("he_abs", jnum(run.scene_error.he_abs));
    kv("her_abs", jnum(run.scene_error.her_abs));
    kv("frames_he_abs_mean", jnum(run.filtered_errors.mean.he_abs));
    kv("frames_her_abs_mean", jnum(run.filtered_errors.mean.her_abs));
    kv("frames_raw_he_abs_mean", jnum(run.raw_errors.mean.he_abs));
    kv("frames_raw_her_abs_mean", jnum(run.raw_errors.mean.her_abs));
  } else {
    kv("he", "null");
    kv("her", "null");
  }
  if (run.box_metric_frames) {
    kv("box_metrics", "{\"frames\": " + std::to_string(run.box_metric_frames) + ", \"cpd\": " +
                          jnum(run.box_metrics.cpd) + ", \"rcpda\": " + jnum(run.box_metrics.rcpda) +
                          ", \"rcpdh\": " + jnum(run.box_metrics.rcpdh) + "}");
  } else {
    kv("box_metrics", "null");
  }
  const shle::HeightOptions& h = o.height;
  kv("options",
     "{\"extend_top\": " + jnum(h.extend_top) + ", \"extend_bottom\": " + jnum(h.extend_bottom) +
         ", \"min_height\": " + jnum(h.min_height) + ", \"kde\": " + (h.use_kde ? "true" : "false") +
         ", \"bandwidth\": " + jnum(h.bandwidth) + ", \"grid_step\": " + jnum(h.grid_step) +
         ", \"depth_filter\": " + (h.use_depth_window ? "true" : "false") + ", \"sigma\": " + jnum(h.sigma) +
         ", \"lowest_n\": " + std::to_string(h.lowest_n) + ", \"kalman\": " +
         (o.temporal.use_kalman ? "true" : "false") + ", \"kalman_compat\": " +
         (o.temporal.kalman_compat ? "true" : "false") + ", \"q\": " + jnum(o.temporal.kalman.q) +
         ", \"r\": " + jnum(o.temporal.kalman.r) + ", \"p0\": " + jnum(o.temporal.kalman.p0) +
         ", \"min_score\": " + jnum(o.box_rule.min_score) + ", \"gate_with_annotations\": " +
         (o.gate_with_annotations ? "true" : "false") + ", \"search_radius\": " +
         std::to_string(o.ncc.search_radius) + "}");
  double s2_sum = 0, s2_max = 0, load_sum = 0, track_sum = 0;
  std::size_t s2_n = 0, load_n = 0, track_n = 0;
  for (const shle::FrameRecord& r : run.frames) {
    if (r.ms_stage2 > 0) s2_sum += r.ms_stage2, s2_max = std::max(s2_max, r.ms_stage2), ++s2_n;
    if (r.ms_load > 0) load_sum += r.ms_load, ++load_n;
    if (r.ms_track > 0) track_sum += r.ms_track, ++track_n;
  }
  kv("timings_ms", "{\"total\": " + jnum(run.ms_total) + ", \"stage2_mean\": " + jnum(s2_n ? s2_sum / s2_n : 0) +
                       ", \"stage2_max\": " + jnum(s2_max) +
                       ", \"disparity_load_mean\": " + jnum(load_n ? load_sum / load_n : 0) +
                       ", \"tracking_mean\": " + jnum(track_n ? track_sum / track_n : 0) + "}");
  std::string problems = "[";
  bool first = true;
  for (const shle::FrameRecord& r : run.frames)
    for (const std::string& p : r.problems) {
      problems += (first ? "\n    " : ",\n    ") + json::quote("frame " + std::to_string(r.index) + ": " + p);
      first = false;
    }
  problems += first ? "]" : "\n  ]";
  kv("problems", problems, true);
  s += "}\n";
  return s;
}

}  // namespace shleapp
