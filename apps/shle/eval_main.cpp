// shle_eval: the tables of docs/SHLE.md on a benchmark written by
// `shle_synth --benchmark DIR`: per-scene HE/HER, the Table III ablation, and
// box sources / box rules / trackers on the simulated detector's boxes; or, with
// `--dataset disparity-height ROOT`, the paper's table over every scene of the
// released Disparity Height layout (apps/shle/dataset_eval.h).
#include <cstdlib>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "apps/common/cli.h"
#include "weights/quote_name.h"
#include "apps/common/exec_env.h"
#include "apps/common/output_files.h"
#include "apps/shle/dataset_eval.h"
#include "apps/shle/detector_option.h"
#include "shle/disparity_height.h"
#include "apps/shle/frame_loader.h"
#include "shle/box_source.h"
#include "shle/error.h"
#include "shle/file_read.h"
#include "shle/pipeline.h"

namespace {

struct BenchScene {
  std::string name, device, dir;
  double height = 0;
};

std::vector<BenchScene> read_listing(const std::string& root) {
  const std::string path = root + "/benchmark.csv";
  std::vector<std::uint8_t> bytes;
  try {
    bytes = shle::read_file_bytes(path, 64ull << 20);
  } catch (const shle::Error& e) {
    throw shle::Error(std::string(e.what()) + " (write it with shle_synth --benchmark)");
  }
  std::istringstream f(std::string(bytes.begin(), bytes.end()));
  std::vector<BenchScene> out;
  std::string line;
  int line_no = 0;
  while (std::getline(f, line)) {
    if (++line_no == 1) continue;  // header
    if (line.empty()) continue;
    std::stringstream ss(line);
    BenchScene s;
    std::string h;
    if (!std::getline(ss, s.name, ',') || !std::getline(ss, s.device, ',') || !std::getline(ss, h, ','))
      throw shle::Error(root + "/benchmark.csv: line " + std::to_string(line_no) + ": expected scene,device,height");
    // A finite positive number, all of the field (std::stod would say only "stod").
    char* end = nullptr;
    s.height = std::strtod(h.c_str(), &end);
    if (h.empty() || *end != '\0' || !std::isfinite(s.height) || !(s.height > 0))
      throw shle::Error(root + "/benchmark.csv: line " + std::to_string(line_no) + ": height " +
                        weights::quote_name(h) + " is not a positive finite number of metres");
    s.dir = root + "/" + s.name;
    out.push_back(s);
  }
  if (out.empty()) throw shle::Error(root + "/benchmark.csv: no scenes");
  return out;
}

struct Aggregate {
  double scene_he_abs = 0, scene_her_abs = 0, scene_he = 0, frame_he_abs = 0, frame_her_abs = 0;
  double cpd = 0, rcpda = 0, rcpdh = 0;
  std::size_t scenes = 0, scenes_with_height = 0, frames = 0, frames_box = 0, frames_used = 0, tracked = 0;
  std::size_t box_scenes = 0;
  void add(const shle::SequenceRun& r) {
    ++scenes;
    frames += r.frames.size();
    frames_box += r.frames_with_box;
    frames_used += r.frames_used;
    tracked += r.frames_tracked;
    if (r.has_errors) {
      ++scenes_with_height;
      scene_he_abs += r.scene_error.he_abs;
      scene_her_abs += r.scene_error.her_abs;
      scene_he += r.scene_error.he;
      frame_he_abs += r.filtered_errors.mean.he_abs;
      frame_her_abs += r.filtered_errors.mean.her_abs;
    }
    if (r.box_metric_frames) {
      ++box_scenes;
      cpd += r.box_metrics.cpd;
      rcpda += r.box_metrics.rcpda;
      rcpdh += r.box_metrics.rcpdh;
    }
  }
  double m(double v) const { return scenes_with_height ? v / scenes_with_height : NAN; }
  double b(double v) const { return box_scenes ? v / box_scenes : NAN; }
};

shle::SequenceRun run_one(const BenchScene& s, shle::BoxSource& src, const shle::PipelineOptions& base) {
  shle::Sequence seq = shle::scan_sequence(s.dir);
  shle::Calibration cal = shle::load_calibration(s.dir + "/calib.json");
  shle::PipelineOptions o = base;
  o.has_gt_height = true;
  o.gt_height = s.height;
  shleapp::PngFrameLoader loader;
  return shle::run_sequence(seq, cal, src, loader, o);
}

shle::SequenceRun run_annotations(const BenchScene& s, const shle::PipelineOptions& o) {
  shle::AnnotationBoxSource src;
  return run_one(s, src, o);
}

shle::SequenceRun run_detections(const BenchScene& s, const shle::PipelineOptions& o) {
  shle::Sequence seq = shle::scan_sequence(s.dir);
  shle::BoxesFileSource src(s.dir + "/detections.csv", seq.frames.size());
  return run_one(s, src, o);
}

}  // namespace

int main(int argc, char** argv) {
  apps::apply_exec_environment("shle_eval");
  std::string root, dataset, gt_file, gt_args, scenes_arg, csv_path, json_path;
  std::vector<std::string> positional;
  bool gate = false, compat = false, no_kalman = false, quiet = false;
  shleapp::DatasetEvalOptions dopt;
  cli::Parser p("shle_eval", "--benchmark DIR | --dataset disparity-height ROOT [options]",
                "Runs shle over the synthetic benchmark written by `shle_synth --benchmark DIR` and prints\n"
                "the HE/HER table, the Table III ablation and the box source / tracker comparison (Markdown);\n"
                "or over every scene of the released Disparity Height layout (ROOT/val/images_0XX/,\n"
                "ROOT/adas_params/) and prints the paper's table: HE, HER %, CPD, RCPDA, RCPDH per scene and\n"
                "overall.");
  p.option("benchmark", "DIR", "benchmark folder with benchmark.csv and scene_*/", &root);
  p.option("dataset", "KIND", "disparity-height, followed by the dataset ROOT (the released data/demo_data)",
           &dataset);
  p.positionals("ROOT", "the dataset root after --dataset disparity-height", &positional);
  p.option("boxes", "SRC",
           "dataset: annotations (default), released-stage1 (--boxes-dir holds images_0XX/ folders of "
           "[[x, y], [w, h]] files, the released tracking_mil_json) or coco-results (--boxes-dir holds "
           "coco_instances_images0XX_results.json) or detector (a Faster R-CNN on every left image: --detector-model, "
           "--detector-weights, e.g. the released model_final.pth converted by weights/export.py)",
           &dopt.boxes);
  shleapp::DetectorChoice det;
  shleapp::add_detector_options(p, &det, "dataset: ");
  p.option("boxes-dir", "DIR", "dataset: folder of the released-stage1 / coco-results box files", &dopt.boxes_dir);
  p.option("coco-images-dir", "DIR|sorted",
           "dataset, coco-results: folder of test2017_images_0XX.json (maps image_id to an image), or 'sorted'",
           &dopt.coco_images_dir);
  p.option("gt-heights", "FILE", "dataset: truth table, lines scene,height (replaces the released 17, 18, 19)",
           &gt_file);
  p.option("gt-height", "S=M,..", "dataset: truth heights on top of the table, e.g. 17=2.85,15=2.85", &gt_args);
  p.option("scenes", "LIST", "dataset: only these scenes, e.g. 17,18 (default every images_0XX)", &scenes_arg);
  p.option("box-rule", "RULE", "dataset: paper (default) or widest (the default with coco-results)", &dopt.box_rule);
  p.option("tracker", "KIND", "dataset: ncc (default), mil or none (the default with released-stage1)",
           &dopt.tracker);
  p.flag("gate-with-annotations", "dataset: the released frame gate against the LabelMe boxes (uses the truth)",
         &gate);
  p.flag("kalman-compat", "dataset: the released Kalman off-by-one", &compat);
  p.flag("no-kalman", "dataset: no temporal filter", &no_kalman);
  p.option("csv", "FILE", "dataset: also write the table as CSV", &csv_path);
  p.option("json", "FILE", "dataset: also write the table and options as JSON", &json_path);
  p.flag("quiet", "dataset: no progress lines on stderr", &quiet);
  p.epilog(
      "examples:\n"
      "  shle_eval --benchmark /tmp/shle_bm\n"
      "  shle_eval --dataset disparity-height data/demo_data --csv table.csv\n"
      "  shle_eval --dataset disparity-height data/demo_data --boxes released-stage1 \\\n"
      "            --boxes-dir Stage1/faster_rcnn_output/tracking_mil_json --gate-with-annotations --kalman-compat\n"
      "  shle_eval --dataset disparity-height data/demo_data --boxes detector --box-rule widest \\\n"
      "            --detector-model detectron2_faster_rcnn_r50_fpn --detector-weights model_final.safetensors");
  p.parse(argc, argv);
  if (p.given("dataset") == p.given("benchmark")) p.fail("give exactly one of --benchmark DIR or --dataset KIND ROOT");
  if (p.given("dataset")) {
    if (dataset != "disparity-height") p.fail("--dataset must be disparity-height");
    if (positional.size() != 1) p.fail("--dataset disparity-height takes the dataset ROOT after it");
    if (!p.given("box-rule") && dopt.boxes == "coco-results") dopt.box_rule = "widest";
    if (!p.given("tracker") && dopt.boxes == "released-stage1") dopt.tracker = "none";
    shleapp::check_detector_options(p, dopt.boxes == "detector", &det);
    dopt.pipeline.gate_with_annotations = gate;
    dopt.pipeline.temporal.kalman_compat = compat;
    dopt.pipeline.temporal.use_kalman = !no_kalman;
    try {
      dopt.gt = p.given("gt-heights") ? shle::load_gt_heights(gt_file) : shle::released_gt_heights();
      if (p.given("gt-height")) shle::parse_gt_height_args(gt_args, &dopt.gt);
      if (p.given("scenes")) {
        std::stringstream ss(scenes_arg);
        std::string item;
        while (std::getline(ss, item, ',')) {
          const int id = shle::parse_scene_id(item);
          if (id < 0) p.fail("--scenes takes scene numbers, e.g. 17,18");
          dopt.scenes.push_back(id);
        }
        if (dopt.scenes.empty()) p.fail("--scenes takes scene numbers, e.g. 17,18");
      }
      shle::parse_box_rule(dopt.box_rule);
      shle::make_tracker(dopt.tracker, {}, {});
      outputs::Plan plan;
      if (p.given("gt-heights")) plan.input(gt_file, "truth table");
      if (dopt.boxes == "detector") plan.input(det.weights, "detector weights");
      if (!csv_path.empty()) plan.output(csv_path);
      if (!json_path.empty()) plan.output(json_path);
      plan.check();
      outputs::install_interrupt_cleanup();
      std::unique_ptr<shle::BoxSource> detector;
      if (dopt.boxes == "detector") {
        shleapp::DetectorDescription described;
        detector = shleapp::make_detector_source(det, "shle_eval", quiet, &described);
        dopt.detector = detector.get();
      }
      shleapp::DatasetEval ev = shleapp::evaluate_dataset(positional.front(), dopt, [&](const shle::DisparityHeightScene& s) {
        if (!quiet) std::fprintf(stderr, "shle_eval: %s\n", s.name.c_str());
      });
      for (const shleapp::SceneEval& s : ev.scenes)
        if (!s.has_gt)
          std::fprintf(stderr, "shle_eval: warning: %s has no truth height (pass --gt-height %d=M): no HE/HER\n",
                       s.scene.name.c_str(), s.scene.id);
      outputs::FileSet set;
      if (!csv_path.empty()) set.add(csv_path, shleapp::dataset_table_csv(ev));
      if (!json_path.empty()) set.add(json_path, shleapp::dataset_table_json(ev));
      set.commit();
      std::printf("%s", shleapp::dataset_table_markdown(ev).c_str());
      return 0;
    } catch (const std::exception& e) {
      std::fprintf(stderr, "shle_eval: %s\n", e.what());
      return 1;
    }
  }
  if (!positional.empty()) p.fail("unexpected argument '" + positional.front() + "'");
  for (const char* o : {"boxes", "boxes-dir", "coco-images-dir", "gt-heights", "gt-height", "scenes", "box-rule", "tracker",
                        "gate-with-annotations", "kalman-compat", "no-kalman", "csv", "json", "quiet", "detector-weights",
                        "detector-model", "detector-score", "detector-labels", "threads"})
    if (p.given(o)) p.fail(std::string("--") + o + " applies to --dataset, not to --benchmark");
  try {
    std::vector<BenchScene> scenes = read_listing(root);

    std::printf("### Per scene (annotation boxes, defaults)\n\n");
    std::printf("| scene | device | truth m | frames used | scene height m | HE m | HER %% | frame mean abs HE m (raw) |\n");
    std::printf("|---|---|---|---|---|---|---|---|\n");
    Aggregate full;
    for (const BenchScene& s : scenes) {
      shle::SequenceRun r = run_annotations(s, {});
      full.add(r);
      if (r.has_errors)
        std::printf("| %s | %s | %.2f | %zu/%zu | %.3f | %+.3f | %+.2f | %.3f (%.3f) |\n", s.name.c_str(),
                    s.device.c_str(), s.height, r.frames_used, r.frames.size(), r.heights.scene_height,
                    r.scene_error.he, 100 * r.scene_error.her, r.filtered_errors.mean.he_abs,
                    r.raw_errors.mean.he_abs);
      else
        std::printf("| %s | %s | %.2f | 0/%zu | - | - | - | - |\n", s.name.c_str(), s.device.c_str(), s.height,
                    r.frames.size());
      std::fflush(stdout);
    }
    std::printf("| **mean of abs** | | | %zu/%zu | | %.3f | %.2f | %.3f |\n\n", full.frames_used, full.frames,
                full.m(full.scene_he_abs), 100 * full.m(full.scene_her_abs), full.m(full.frame_he_abs));

    struct Variant {
      const char* name;
      shle::PipelineOptions options;
    };
    std::vector<Variant> ablation;
    shle::PipelineOptions o;
    ablation.push_back({"Full (released defaults)", o});
    o = {};
    o.height.extend_top = o.height.extend_bottom = 0;
    ablation.push_back({"- Pixel extension", o});
    o = {};
    o.height.use_depth_window = false;
    ablation.push_back({"- Depth filter", o});
    o = {};
    o.height.use_kde = false;
    ablation.push_back({"- KDE (mean depth)", o});
    o = {};
    o.height.lowest_n = 1;
    ablation.push_back({"- Average lowest points (N = 1)", o});
    o = {};
    o.temporal.use_kalman = false;
    ablation.push_back({"- Kalman", o});
    o = {};
    o.temporal.kalman_compat = true;
    ablation.push_back({"Released Kalman off-by-one", o});
    o = {};
    o.height.grid_step = 0.1;
    ablation.push_back({"KDE grid 0.1 m (improvement)", o});
    std::printf("### Ablation (Table III style)\n\n");
    std::printf("Annotation boxes, and the simulated detector's boxes with the paper rule and the NCC tracker.\n\n");
    std::printf("| configuration | annotations: mean abs scene HE m | HER %% | signed HE m | frame mean abs HE m "
                "| detector: mean abs scene HE m | HER %% | signed HE m | frame mean abs HE m |\n");
    std::printf("|---|---|---|---|---|---|---|---|---|\n");
    for (const Variant& v : ablation) {
      Aggregate a, d;
      for (const BenchScene& s : scenes) {
        a.add(run_annotations(s, v.options));
        d.add(run_detections(s, v.options));
      }
      std::printf("| %s | %.3f | %.2f | %+.3f | %.3f | %.3f | %.2f | %+.3f | %.3f |\n", v.name, a.m(a.scene_he_abs),
                  100 * a.m(a.scene_her_abs), a.m(a.scene_he), a.m(a.frame_he_abs), d.m(d.scene_he_abs),
                  100 * d.m(d.scene_her_abs), d.m(d.scene_he), d.m(d.frame_he_abs));
      std::fflush(stdout);
    }
    std::printf("\n### Simulated detector boxes (detections.csv): box rule and tracker\n\n");
    std::printf("| box rule | tracker | frames with box | tracked | CPD px | RCPDA | RCPDH | mean abs scene HE m | mean abs scene HER %% | frame mean abs HE m |\n");
    std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
    for (shle::BoxRule rule : {shle::BoxRule::Paper, shle::BoxRule::Widest})
      for (const char* tracker : {"ncc", "mil", "none"}) {
        shle::PipelineOptions d;
        d.box_rule.rule = rule;
        d.tracker = tracker;
        Aggregate a;
        for (const BenchScene& s : scenes) a.add(run_detections(s, d));
        std::printf("| %s | %s | %zu/%zu | %zu | %.1f | %.5f | %.3f | %.3f | %.2f | %.3f |\n",
                    shle::box_rule_name(rule), tracker, a.frames_box, a.frames, a.tracked, a.b(a.cpd), a.b(a.rcpda),
                    a.b(a.rcpdh), a.m(a.scene_he_abs), 100 * a.m(a.scene_her_abs), a.m(a.frame_he_abs));
        std::fflush(stdout);
      }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "shle_eval: %s\n", e.what());
    return 1;
  }
}
