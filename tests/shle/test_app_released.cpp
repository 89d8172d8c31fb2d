// The shle and shle_eval binaries on the released artefacts: usage errors of
// --boxes released-stage1 / coco-results, the gate's report, and
// shle_eval --dataset disparity-height on a dataset written by
// shle_synth --disparity-height (table, CSV, JSON, truth tables, errors).
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "tests/shle/test_util.h"
#include "weights/json.h"

namespace {

namespace fs = std::filesystem;
using shletest::TempDir;
using shletest::write_text;

using shletest::Result;
using shletest::run;
using shletest::slurp;

// A 4-frame Disparity Height dataset (scenes 17, 18, 19), written once.
const std::string& dataset() {
  static TempDir dir;
  static const std::string root = [] {
    std::string r = dir / "demo_data";
    std::string cmd = std::string(SHLE_SYNTH_APP) + " --disparity-height --out '" + r + "' --frames 4 --quiet";
    if (std::system(cmd.c_str()) != 0) throw std::runtime_error("shle_synth --disparity-height failed");
    return r;
  }();
  return root;
}

std::string shle_on_17() {
  const std::string s = dataset() + "/val/images_017";
  return std::string(SHLE_APP) + " --sequence '" + s + "' --calib '" + dataset() +
         "/adas_params' --calib-format smartereye --quiet";
}

TEST(ShleAppReleased, UsageErrors) {
  TempDir t;
  Result r = run(shle_on_17() + " --boxes released-stage1 --out-dir '" + (t / "o") + "'", t);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--boxes released-stage1 takes one folder after it"), std::string::npos) << r.err;
  r = run(shle_on_17() + " --boxes coco-results r.json --out-dir '" + (t / "o") + "'", t);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("needs --coco-images FILE"), std::string::npos) << r.err;
  r = run(shle_on_17() + " --boxes annotations extra --out-dir '" + (t / "o") + "'", t);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("unexpected argument 'extra'"), std::string::npos) << r.err;
  r = run(shle_on_17() + " --coco-images sorted --out-dir '" + (t / "o") + "'", t);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--coco-images needs --boxes coco-results"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(t / "o/frames.csv"));
}

TEST(ShleAppReleased, WrongFormatStopsTheRunNamingTheFile) {
  TempDir t;
  // The scene's own LabelMe folder (corners) given as released stage-1 files.
  Result r = run(shle_on_17() + " --boxes released-stage1 '" + dataset() + "/val/images_017/left_colorimages' --out-dir '" +
                     (t / "o") + "'",
                 t);
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find(".json: written by LabelMe"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_FALSE(fs::exists(t / "o/frames.csv"));
  write_text(t / "r.json", R"([{"image_id": 1, "category_id": 1, "bbox": [1, 2, 3], "score": 0.9}])");
  r = run(shle_on_17() + " --boxes coco-results '" + (t / "r.json") + "' --coco-images sorted --out-dir '" + (t / "o") +
              "'",
          t);
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("r.json: record 0: \"bbox\" must be [x, y, w, h]"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(t / "o/frames.csv"));
}

TEST(ShleAppReleased, GateReportsAndCounts) {
  TempDir t;
  // Frame 1 gets a box far from its annotation, the others none: one gated frame.
  const std::string s = dataset() + "/val/images_017/left_colorimages";
  std::vector<std::string> pngs;
  for (const auto& e : fs::directory_iterator(s))
    if (e.path().extension() == ".png") pngs.push_back(e.path().filename().string());
  std::sort(pngs.begin(), pngs.end());
  ASSERT_EQ(pngs.size(), 4u);
  write_text(t / "r.json", R"([{"image_id": 2, "category_id": 1, "bbox": [20, 600, 1200, 110], "score": 0.9}])");
  Result r = run(shle_on_17() + " --boxes coco-results '" + (t / "r.json") +
                     "' --coco-images sorted --gate-with-annotations --out-dir '" + (t / "o") + "'",
                 t);
  EXPECT_EQ(r.code, 0) << r.err;
  json::Value sum = json::parse(slurp(t / "o/summary.json"), "summary.json");
  EXPECT_EQ(sum.get("frames_with_box")->number(), 1);
  EXPECT_EQ(sum.get("frames_gated_out")->number(), 1);
  EXPECT_EQ(sum.get("frames_used")->number(), 0);
  EXPECT_TRUE(sum.get("options")->get("gate_with_annotations")->boolean());
  EXPECT_EQ(sum.get("box_rule")->str(), "widest");
  EXPECT_NE(slurp(t / "o/summary.json").find("gated out: the box does not hit the annotation box"), std::string::npos);
  // Without the gate the same frame gets a height.
  r = run(shle_on_17() + " --boxes coco-results '" + (t / "r.json") + "' --coco-images sorted --out-dir '" + (t / "o2") +
              "'",
          t);
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(json::parse(slurp(t / "o2/summary.json"), "s").get("frames_gated_out")->number(), 0);
}

TEST(ShleEvalDataset, TableCsvJson) {
  TempDir t;
  Result r = run(std::string(SHLE_EVAL_APP) + " --dataset disparity-height '" + dataset() + "' --quiet --csv '" +
                     (t / "t.csv") + "' --json '" + (t / "t.json") + "'",
                 t);
  ASSERT_EQ(r.code, 0) << r.err;
  for (const char* scene : {"| images_017 | 2.85 | 4 |", "| images_018 | 2.20 | 4 |", "| images_019 | 5.30 | 4 |",
                            "| **overall** | | 12 |", "| **mean of abs** |"})
    EXPECT_NE(r.out.find(scene), std::string::npos) << scene << "\n" << r.out;
  std::string csv = slurp(t / "t.csv");
  EXPECT_EQ(csv.rfind("scene,truth_m,frames,", 0), 0u) << csv;
  EXPECT_NE(csv.find("\nimages_019,5.3,4,4,0,"), std::string::npos) << csv;
  EXPECT_NE(csv.find("\noverall,,12,12,0,"), std::string::npos) << csv;
  json::Value j = json::parse(slurp(t / "t.json"), "t.json");
  ASSERT_EQ(j.get("scenes")->array().size(), 3u);
  const json::Value& s17 = j.get("scenes")->array()[0];
  EXPECT_EQ(s17.get("id")->number(), 17);
  EXPECT_EQ(s17.get("truth")->number(), 2.85);
  // The synthetic bar: HE within 0.2 m (a wrong calibration or box would be metres off).
  EXPECT_LT(std::fabs(s17.get("he")->number()), 0.2);
  EXPECT_EQ(s17.get("cpd")->number(), 0);  // annotation boxes against themselves
  EXPECT_EQ(j.get("overall")->get("scenes_with_error")->number(), 3);

  // Truth tables: a file replaces the released three, --gt-height adds on top.
  write_text(t / "gt.csv", "scene,height\n17,3.0\n");
  r = run(std::string(SHLE_EVAL_APP) + " --dataset disparity-height '" + dataset() + "' --quiet --scenes 17,19 " +
              "--gt-heights '" + (t / "gt.csv") + "' --gt-height 19=5.0 --json '" + (t / "u.json") + "'",
          t);
  ASSERT_EQ(r.code, 0) << r.err;
  j = json::parse(slurp(t / "u.json"), "u.json");
  ASSERT_EQ(j.get("scenes")->array().size(), 2u);
  EXPECT_EQ(j.get("scenes")->array()[0].get("truth")->number(), 3.0);
  EXPECT_EQ(j.get("scenes")->array()[1].get("truth")->number(), 5.0);
  // A scene without a truth: a row without HE and a warning.
  write_text(t / "gt17.csv", "17,2.85\n");
  r = run(std::string(SHLE_EVAL_APP) + " --dataset disparity-height '" + dataset() + "' --quiet --gt-heights '" +
              (t / "gt17.csv") + "'",
          t);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("images_018 has no truth height (pass --gt-height 18=M)"), std::string::npos) << r.err;
  EXPECT_NE(r.out.find("| images_018 | - | 4 |"), std::string::npos) << r.out;
}

TEST(ShleEvalDataset, Errors) {
  TempDir t;
  auto eval = [&](const std::string& args) { return run(std::string(SHLE_EVAL_APP) + " " + args, t); };
  Result r = eval("--dataset disparity-height");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("takes the dataset ROOT"), std::string::npos) << r.err;
  r = eval("--dataset kitti '" + dataset() + "'");
  EXPECT_EQ(r.code, 2);
  r = eval("--dataset disparity-height '" + dataset() + "' --benchmark x");
  EXPECT_EQ(r.code, 2);
  r = eval("--benchmark '" + (t / "bm") + "' --csv x.csv");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--csv applies to --dataset"), std::string::npos) << r.err;
  r = eval("--dataset disparity-height '" + (t / "none") + "'");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("none: no such dataset folder"), std::string::npos) << r.err;
  r = eval("--dataset disparity-height '" + dataset() + "' --scenes 20");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("no scene images_020"), std::string::npos) << r.err;
  write_text(t / "bad.csv", "17,abc\n");
  r = eval("--dataset disparity-height '" + dataset() + "' --gt-heights '" + (t / "bad.csv") + "' --csv '" +
           (t / "o.csv") + "'");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("bad.csv: line 1: height 'abc'"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(t / "o.csv"));
  write_text(t / "empty.csv", "");
  r = eval("--dataset disparity-height '" + dataset() + "' --gt-heights '" + (t / "empty.csv") + "'");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("empty.csv: no scene,height line"), std::string::npos) << r.err;
  r = eval("--dataset disparity-height '" + dataset() + "' --gt-height 17");
  EXPECT_EQ(r.code, 1);
  r = eval("--dataset disparity-height '" + dataset() + "' --boxes released-stage1 --boxes-dir '" + (t / "st") +
           "' --csv '" + (t / "o.csv") + "'");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("st/images_017: no such folder"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(t / "o.csv"));
}

// The paper's table straight from a detector (the released model_final.pth's
// network, here seeded random weights under its names), loaded once for every scene.
TEST(ShleEvalDataset, DetectorOnEveryScene) {
  TempDir t;
  const std::string w = t / "d2.safetensors";
  ASSERT_EQ(std::system((std::string(SYNTH_APP) + " --model detectron2_faster_rcnn_r50_fpn --classes 1 --out '" + w +
                         "' > /dev/null")
                            .c_str()),
            0);
  const std::string base = std::string(SHLE_EVAL_APP) + " --dataset disparity-height '" + dataset() + "' --scenes 17,18";
  Result r = run(base + " --boxes detector --detector-model detectron2_faster_rcnn_r50_fpn --detector-weights '" + w +
                     "' --detector-score 0 --box-rule widest --threads 2 --json '" + (t / "d.json") + "'",
                 t);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 3) << r.err;  // the detector once, then the two scenes
  EXPECT_NE(r.err.find("shle_eval: detector detectron2_faster_rcnn_r50_fpn, 1 classes (score > 0)"), std::string::npos)
      << r.err;
  EXPECT_NE(r.out.find("| images_017 | 2.85 | 4 |"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("| images_018 | 2.20 | 4 |"), std::string::npos) << r.out;
  json::Value j = json::parse(slurp(t / "d.json"), "d.json");
  EXPECT_EQ(j.get("box_source")->str(), "detector");
  ASSERT_EQ(j.get("scenes")->array().size(), 2u);

  // The detector options belong to --boxes detector, and it needs its weights.
  r = run(base + " --detector-weights '" + w + "'", t);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--detector-weights needs --boxes detector"), std::string::npos) << r.err;
  r = run(base + " --boxes detector", t);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--boxes detector needs --detector-weights"), std::string::npos) << r.err;
  r = run(base + " --boxes detector --detector-weights '" + (t / "none.safetensors") + "' --json '" + (t / "n.json") + "'",
          t);
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("none.safetensors"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(t / "n.json"));
}

}  // namespace
