#include "apps/shle/dataset_eval.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "apps/shle/frame_loader.h"
#include "shle/box_source.h"
#include "shle/error.h"
#include "shle/released_box_source.h"
#include "weights/json.h"

namespace shleapp {
namespace {

std::string scene_number(int id) {
  char b[16];
  std::snprintf(b, sizeof b, "%03d", id);
  return b;
}

std::string fmt(const char* f, double v) {
  if (!std::isfinite(v)) return "";
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

std::string jnum(double v) { return std::isfinite(v) ? fmt("%.10g", v) : "null"; }

struct Overall {
  std::size_t frames = 0, with_box = 0, used = 0, gated = 0, scenes_he = 0, box_frames = 0;
  double he = 0, her = 0, he_abs = 0, her_abs = 0, frame_he_abs = 0, cpd = 0, rcpda = 0, rcpdh = 0;
  double mean(double v) const { return scenes_he ? v / scenes_he : NAN; }
  double box(double v) const { return box_frames ? v / box_frames : NAN; }
};

Overall overall(const DatasetEval& e) {
  Overall o;
  for (const SceneEval& s : e.scenes) {
    const shle::SequenceRun& r = s.run;
    o.frames += r.frames.size();
    o.with_box += r.frames_with_box;
    o.used += r.frames_used;
    o.gated += r.frames_gated_out;
    if (r.has_errors) {
      ++o.scenes_he;
      o.he += r.scene_error.he;
      o.her += r.scene_error.her;
      o.he_abs += r.scene_error.he_abs;
      o.her_abs += r.scene_error.her_abs;
      o.frame_he_abs += r.filtered_errors.mean.he_abs;
    }
    const double n = static_cast<double>(r.box_metric_frames);
    o.box_frames += r.box_metric_frames;
    o.cpd += r.box_metrics.cpd * n;
    o.rcpda += r.box_metrics.rcpda * n;
    o.rcpdh += r.box_metrics.rcpdh * n;
  }
  return o;
}

double box_metric(const shle::SequenceRun& r, double v) { return r.box_metric_frames ? v : NAN; }

}  // namespace

DatasetEval evaluate_dataset(const std::string& root, const DatasetEvalOptions& opt,
                             const std::function<void(const shle::DisparityHeightScene&)>& progress) {
  namespace fs = std::filesystem;
  DatasetEval out;
  out.root = root;
  out.options = opt;
  shle::DisparityHeightDataset d = shle::scan_disparity_height(root);
  std::vector<shle::DisparityHeightScene> scenes;
  if (opt.scenes.empty()) {
    scenes = d.scenes;
  } else {
    for (int id : opt.scenes) {
      bool found = false;
      for (const auto& s : d.scenes) found = found || (s.id == id && (scenes.push_back(s), true));
      if (!found) throw shle::Error(root + "/val: no scene images_" + scene_number(id));
    }
  }
  const shle::Calibration cal = shle::load_smartereye_calibration(d.adas_params);
  if (opt.boxes != "annotations" && opt.boxes != "released-stage1" && opt.boxes != "coco-results" &&
      opt.boxes != "detector")
    throw shle::Error("box source must be annotations, released-stage1, coco-results or detector");
  if (opt.boxes == "detector" && !opt.detector) throw shle::Error("--boxes detector needs a loaded detector");
  if ((opt.boxes == "released-stage1" || opt.boxes == "coco-results") && opt.boxes_dir.empty())
    throw shle::Error("--boxes " + opt.boxes + " needs --boxes-dir DIR");
  if (opt.boxes == "coco-results" && opt.coco_images_dir.empty())
    throw shle::Error("--boxes coco-results needs --coco-images-dir DIR (test2017_images_0XX.json) or 'sorted'");
  for (const auto& s : scenes) {
    if (progress) progress(s);
    SceneEval e;
    e.scene = s;
    auto gt = opt.gt.find(s.id);
    e.has_gt = gt != opt.gt.end();
    e.gt = e.has_gt ? gt->second : 0;
    shle::PipelineOptions po = opt.pipeline;
    po.has_gt_height = e.has_gt;
    po.gt_height = e.gt;
    po.tracker = opt.tracker;
    po.box_rule.rule = shle::parse_box_rule(opt.box_rule);
    shle::Sequence seq = shle::scan_sequence(s.dir);
    PngFrameLoader loader;
    std::unique_ptr<shle::BoxSource> src;
    const std::string num = scene_number(s.id);
    if (opt.boxes == "annotations") {
      src = std::make_unique<shle::AnnotationBoxSource>();
    } else if (opt.boxes == "released-stage1") {
      src = std::make_unique<shle::ReleasedStage1Source>((fs::path(opt.boxes_dir) / ("images_" + num)).string(), seq,
                                                         shle::sequence_image_sizes(seq, loader, cal));
    } else if (opt.boxes == "coco-results") {
      const std::string results = (fs::path(opt.boxes_dir) / ("coco_instances_images" + num + "_results.json")).string();
      const std::string images = opt.coco_images_dir == "sorted"
                                     ? std::string("sorted")
                                     : (fs::path(opt.coco_images_dir) / ("test2017_images_" + num + ".json")).string();
      src = std::make_unique<shle::CocoResultsSource>(results, images, seq, shle::sequence_image_sizes(seq, loader, cal));
    }
    // "detector": the caller's source, loaded once, for every scene.
    e.run = shle::run_sequence(seq, cal, src ? *src : *opt.detector, loader, po);
    out.scenes.push_back(std::move(e));
  }
  return out;
}

std::string dataset_table_markdown(const DatasetEval& e) {
  std::string s =
      "| scene | truth m | frames | with box | gated out | used | scene height m | HE m | HER % | frame mean abs HE m "
      "| CPD px | RCPDA | RCPDH |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  auto cell = [](const std::string& v) { return v.empty() ? std::string("-") : v; };
  for (const SceneEval& x : e.scenes) {
    const shle::SequenceRun& r = x.run;
    s += "| " + x.scene.name + " | " + (x.has_gt ? fmt("%.2f", x.gt) : "-") + " | " + std::to_string(r.frames.size()) +
         " | " + std::to_string(r.frames_with_box) + " | " + std::to_string(r.frames_gated_out) + " | " +
         std::to_string(r.frames_used) + " | " +
         cell(r.heights.has_scene_height ? fmt("%.3f", r.heights.scene_height) : "") + " | " +
         cell(r.has_errors ? fmt("%+.3f", r.scene_error.he) : "") + " | " +
         cell(r.has_errors ? fmt("%+.2f", 100 * r.scene_error.her) : "") + " | " +
         cell(r.has_errors ? fmt("%.3f", r.filtered_errors.mean.he_abs) : "") + " | " +
         cell(fmt("%.2f", box_metric(r, r.box_metrics.cpd))) + " | " + cell(fmt("%.5f", box_metric(r, r.box_metrics.rcpda))) +
         " | " + cell(fmt("%.3f", box_metric(r, r.box_metrics.rcpdh))) + " |\n";
  }
  const Overall o = overall(e);
  s += "| **overall** | | " + std::to_string(o.frames) + " | " + std::to_string(o.with_box) + " | " +
       std::to_string(o.gated) + " | " + std::to_string(o.used) + " | | " + cell(fmt("%+.3f", o.mean(o.he))) + " | " +
       cell(fmt("%+.2f", 100 * o.mean(o.her))) + " | " + cell(fmt("%.3f", o.mean(o.frame_he_abs))) + " | " +
       cell(fmt("%.2f", o.box(o.cpd))) + " | " + cell(fmt("%.5f", o.box(o.rcpda))) + " | " +
       cell(fmt("%.3f", o.box(o.rcpdh))) + " |\n";
  s += "| **mean of abs** | | | | | | | " + cell(fmt("%.3f", o.mean(o.he_abs))) + " | " +
       cell(fmt("%.2f", 100 * o.mean(o.her_abs))) + " | | | | |\n";
  return s;
}

std::string dataset_table_csv(const DatasetEval& e) {
  std::string s =
      "scene,truth_m,frames,frames_with_box,frames_gated_out,frames_used,scene_height_m,he_m,her_percent,"
      "he_abs_m,her_abs_percent,frame_mean_abs_he_m,cpd_px,rcpda,rcpdh\n";
  for (const SceneEval& x : e.scenes) {
    const shle::SequenceRun& r = x.run;
    const bool he = r.has_errors;
    s += x.scene.name + "," + (x.has_gt ? fmt("%.10g", x.gt) : "") + "," + std::to_string(r.frames.size()) + "," +
         std::to_string(r.frames_with_box) + "," + std::to_string(r.frames_gated_out) + "," +
         std::to_string(r.frames_used) + "," +
         (r.heights.has_scene_height ? fmt("%.17g", r.heights.scene_height) : "") + "," +
         (he ? fmt("%.17g", r.scene_error.he) : "") + "," + (he ? fmt("%.17g", 100 * r.scene_error.her) : "") + "," +
         (he ? fmt("%.17g", r.scene_error.he_abs) : "") + "," + (he ? fmt("%.17g", 100 * r.scene_error.her_abs) : "") +
         "," + (he ? fmt("%.17g", r.filtered_errors.mean.he_abs) : "") + "," +
         fmt("%.17g", box_metric(r, r.box_metrics.cpd)) + "," + fmt("%.17g", box_metric(r, r.box_metrics.rcpda)) + "," +
         fmt("%.17g", box_metric(r, r.box_metrics.rcpdh)) + "\n";
  }
  const Overall o = overall(e);
  s += "overall,," + std::to_string(o.frames) + "," + std::to_string(o.with_box) + "," + std::to_string(o.gated) + "," +
       std::to_string(o.used) + ",," + fmt("%.17g", o.mean(o.he)) + "," + fmt("%.17g", 100 * o.mean(o.her)) + "," +
       fmt("%.17g", o.mean(o.he_abs)) + "," + fmt("%.17g", 100 * o.mean(o.her_abs)) + "," +
       fmt("%.17g", o.mean(o.frame_he_abs)) + "," + fmt("%.17g", o.box(o.cpd)) + "," + fmt("%.17g", o.box(o.rcpda)) +
       "," + fmt("%.17g", o.box(o.rcpdh)) + "\n";
  return s;
}

std::string dataset_table_json(const DatasetEval& e) {
  const DatasetEvalOptions& op = e.options;
  std::string s = "{\n  \"dataset\": \"disparity-height\",\n  \"root\": " + json::quote(e.root) +
                  ",\n  \"box_source\": " + json::quote(op.boxes) + ",\n  \"boxes_dir\": " + json::quote(op.boxes_dir) +
                  ",\n  \"box_rule\": " + json::quote(op.box_rule) + ",\n  \"tracker\": " + json::quote(op.tracker) +
                  ",\n  \"gate_with_annotations\": " + (op.pipeline.gate_with_annotations ? "true" : "false") +
                  ",\n  \"kalman\": " + (op.pipeline.temporal.use_kalman ? "true" : "false") +
                  ",\n  \"kalman_compat\": " + (op.pipeline.temporal.kalman_compat ? "true" : "false") +
                  ",\n  \"scenes\": [";
  bool first = true;
  for (const SceneEval& x : e.scenes) {
    const shle::SequenceRun& r = x.run;
    const bool he = r.has_errors;
    s += std::string(first ? "\n" : ",\n") + "    {\"scene\": " + json::quote(x.scene.name) +
         ", \"id\": " + std::to_string(x.scene.id) + ", \"truth\": " + (x.has_gt ? jnum(x.gt) : "null") +
         ", \"frames\": " + std::to_string(r.frames.size()) + ", \"frames_with_box\": " +
         std::to_string(r.frames_with_box) + ", \"frames_gated_out\": " + std::to_string(r.frames_gated_out) +
         ", \"frames_used\": " + std::to_string(r.frames_used) + ", \"scene_height\": " +
         (r.heights.has_scene_height ? jnum(r.heights.scene_height) : "null") + ", \"he\": " +
         (he ? jnum(r.scene_error.he) : "null") + ", \"her\": " + (he ? jnum(r.scene_error.her) : "null") +
         ", \"he_abs\": " + (he ? jnum(r.scene_error.he_abs) : "null") + ", \"her_abs\": " +
         (he ? jnum(r.scene_error.her_abs) : "null") + ", \"frame_mean_abs_he\": " +
         (he ? jnum(r.filtered_errors.mean.he_abs) : "null") + ", \"box_metric_frames\": " +
         std::to_string(r.box_metric_frames) + ", \"cpd\": " + jnum(box_metric(r, r.box_metrics.cpd)) +
         ", \"rcpda\": " + jnum(box_metric(r, r.box_metrics.rcpda)) + ", \"rcpdh\": " +
         jnum(box_metric(r, r.box_metrics.rcpdh)) + "}";
    first = false;
  }
  const Overall o = overall(e);
  s += std::string(first ? "]" : "\n  ]") + ",\n  \"overall\": {\"frames\": " + std::to_string(o.frames) +
       ", \"frames_with_box\": " + std::to_string(o.with_box) + ", \"frames_gated_out\": " + std::to_string(o.gated) +
       ", \"frames_used\": " + std::to_string(o.used) + ", \"scenes_with_error\": " + std::to_string(o.scenes_he) +
       ", \"he\": " + jnum(o.mean(o.he)) + ", \"her\": " + jnum(o.mean(o.her)) + ", \"he_abs\": " +
       jnum(o.mean(o.he_abs)) + ", \"her_abs\": " + jnum(o.mean(o.her_abs)) + ", \"frame_mean_abs_he\": " +
       jnum(o.mean(o.frame_he_abs)) + ", \"box_metric_frames\": " + std::to_string(o.box_frames) + ", \"cpd\": " +
       jnum(o.box(o.cpd)) + ", \"rcpda\": " + jnum(o.box(o.rcpda)) + ", \"rcpdh\": " + jnum(o.box(o.rcpdh)) + "}\n}\n";
  return s;
}

}  // namespace shleapp
