// shle_eval --dataset disparity-height ROOT: every scene of the released
// Disparity Height layout (shle/disparity_height.h) through run_sequence with the
// SmarterEye calibration of ROOT/adas_params, and the paper's table (HE, HER %,
// CPD / RCPDA / RCPDH) per scene and overall, as Markdown, CSV and JSON.
#pragma once

#include <functional>
#include <map>
#include <string>
#include <vector>

#include "shle/box_source.h"
#include "shle/disparity_height.h"
#include "shle/pipeline.h"

namespace shleapp {

struct DatasetEvalOptions {
  // "annotations" (LabelMe beside the images), "released-stage1" (boxes_dir/images_0XX/,
  // the released tracking_<tracker>_json folder) or "coco-results"
  // (boxes_dir/coco_instances_images0XX_results.json, the names demo.sh gives, with
  // coco_images_dir/test2017_images_0XX.json or coco_images_dir == "sorted").
  // "detector": `detector` (loaded once by the caller, e.g. from model_final.pth) finds
  // the candidates on every left image of every scene.
  std::string boxes = "annotations", boxes_dir, coco_images_dir;
  shle::BoxSource* detector = nullptr;
  std::vector<int> scenes;        // empty: every scene
  std::map<int, double> gt;       // scene id -> truth (m)
  shle::PipelineOptions pipeline; // has_gt_height / gt_height set per scene
  std::string box_rule = "paper", tracker = "ncc";
};

struct SceneEval {
  shle::DisparityHeightScene scene;
  bool has_gt = false;
  double gt = 0;
  shle::SequenceRun run;
};

struct DatasetEval {
  std::string root;
  DatasetEvalOptions options;
  std::vector<SceneEval> scenes;
};

// Throws shle::Error for a bad dataset, calibration, box file or option; frame
// problems stay in each run. `progress(scene)` before each scene.
DatasetEval evaluate_dataset(const std::string& root, const DatasetEvalOptions& options,
                             const std::function<void(const shle::DisparityHeightScene&)>& progress = {});

// The per-scene and overall table (Markdown), the same as CSV, and as JSON.
// Overall: frame counts summed; HE and HER the mean over the scenes with a truth
// and a height of the signed values, with the mean of their absolute values
// beside; CPD / RCPDA / RCPDH the mean over every frame with a box and an
// annotation box, all scenes pooled.
std::string dataset_table_markdown(const DatasetEval& eval);
std::string dataset_table_csv(const DatasetEval& eval);
std::string dataset_table_json(const DatasetEval& eval);

}  // namespace shleapp
