// The readers of the released SHLE artefacts (shle/released_boxes.h,
// released_box_source.h, disparity_height.h) on hand-written files and their
// malformed variants, the released frame gate, and the corner / size confusion
// refused in both directions.
#include <gtest/gtest.h>

#include <cmath>

#include "shle/box_source.h"
#include "shle/dataset.h"
#include "shle/disparity_height.h"
#include "shle/error.h"
#include "shle/labelme.h"
#include "shle/released_box_source.h"
#include "shle/released_boxes.h"
#include "shle/released_gate.h"
#include "shle/stream.h"
#include "tests/shle/test_util.h"
#include "weights/json.h"

namespace {

using shletest::TempDir;
using shletest::write_text;

// What the released Stage1/tracking_faster_rcnn.py save_json writes.
std::string stage1(const std::string& points, const std::string& extra_shape = "", const std::string& extra = "") {
  return "{\"version\": \"4.5.9\", \"flags\": {}, \"shapes\": [{\"label\": \"height\", \"points\": " + points +
         ", \"shape_type\": \"rectangle\", \"flags\": {}" + extra_shape + "}], \"imagePath\": \"a.png\"," +
         " \"imageHeight\": 720, \"imageWidth\": 1280" + extra + "}";
}

shle::Box parse_stage1(const std::string& text) {
  return shle::parse_released_stage1(json::parse(text, "s.json"), "s.json", 1280, 720);
}

TEST(ReleasedStage1, ReadsSizeAsCorners) {
  shle::Box b = parse_stage1(stage1("[[497.5, 283.25], [290.25, 29.5]]"));
  EXPECT_EQ(b.x0, 497.5);
  EXPECT_EQ(b.y0, 283.25);
  EXPECT_EQ(b.x1, 787.75);
  EXPECT_EQ(b.y1, 312.75);
  // Touching the border, float32 rounding past it, and a zero size are fine.
  EXPECT_EQ(parse_stage1(stage1("[[0, 0], [1280, 720]]")).x1, 1280);
  EXPECT_EQ(parse_stage1(stage1("[[1000, 600], [280.0001, 120.0001]]")).y0, 600);
  EXPECT_EQ(parse_stage1(stage1("[[10, 10], [0, 0]]")).width(), 0);
  EXPECT_TRUE(shle::has_released_stage1_layout(json::parse(stage1("[[1, 2], [3, 4]]"), "s")));
}

TEST(ReleasedStage1, Malformed) {
  auto bad = [](const std::string& text, const char* msg) { EXPECT_THROW_MSG(parse_stage1(text), msg); };
  bad("[]", "must be a JSON object");
  bad("{}", "no \"shapes\" array");
  bad(R"({"shapes": {}})", "no \"shapes\" array");
  bad(R"({"shapes": []})", "0 shapes");
  bad(R"({"shapes": [{"label": "height", "points": [[1, 2], [3, 4]]}, {"label": "height", "points": [[1, 2], [3, 4]]}]})",
      "2 shapes");
  bad(R"({"shapes": [3]})", "shape 0 is not an object");
  bad(R"({"shapes": [{"points": [[1, 2], [3, 4]]}]})", "no string \"label\"");
  bad(R"({"shapes": [{"label": "car", "points": [[1, 2], [3, 4]]}]})", "labelled 'car'");
  bad(R"({"shapes": [{"label": "height"}]})", "no \"points\" array");
  // Wrong shape of points.
  bad(stage1("[[1, 2]]"), "has 1 points");
  bad(stage1("[[1, 2], [3, 4], [5, 6]]"), "has 3 points");
  bad(stage1("[[1, 2], [3]]"), "point 1 is not a pair of numbers");
  bad(stage1("[[1, 2], 3]"), "point 1 is not a pair of numbers");
  bad(stage1("[[1, \"2\"], [3, 4]]"), "point 0 is not a pair of numbers");
  bad(stage1("[[1, 2], [3, 1e999]]"), "number is too large");  // the JSON reader never yields inf
  // Sizes that are not sizes, and boxes outside the image.
  bad(stage1("[[500, 300], [-10, 20]]"), "negative size");
  bad(stage1("[[-5, 300], [10, 20]]"), "starts outside the image");
  bad(stage1("[[500, 300], [790, 330]]"), "ends at (x + w, y + h) = (1290, 630), outside the 1280x720 image");
  bad(stage1("[[100, 500], [200, 240]]"), "outside the 1280x720 image");
  // A LabelMe corner file (LabelMe always writes imageData and group_id).
  bad(stage1("[[100, 200], [300, 260]]", ", \"group_id\": null"), "written by LabelMe");
  bad(stage1("[[100, 200], [300, 260]]", "", ", \"imageData\": null"), "read it with --boxes annotations");
  bad(R"({"shapes": [{"label": "height", "points": [[1, 2], [3, 4]]}], "imageWidth": 0})", "\"imageWidth\"");
  bad(R"({"shapes": [{"label": "height", "points": [[1, 2], [3, 4]]}], "imageHeight": 1e6})", "beyond 65535");
}

TEST(ReleasedStage1, FilesEmptyNanAndMissing) {
  TempDir dir;
  write_text(dir / "empty.json", "");
  EXPECT_THROW_MSG(shle::load_released_stage1(dir / "empty.json", 1280, 720), "empty.json: empty file");
  // Python's json.dump writes NaN for a NaN box; JSON has no NaN.
  write_text(dir / "nan.json", stage1("[[NaN, 2], [3, 4]]"));
  EXPECT_THROW_MSG(shle::load_released_stage1(dir / "nan.json", 1280, 720), "nan.json");
  write_text(dir / "trunc.json", stage1("[[1, 2], [3, 4]]").substr(0, 40));
  EXPECT_THROW_MSG(shle::load_released_stage1(dir / "trunc.json", 1280, 720), "trunc.json");
  EXPECT_THROW_MSG(shle::load_released_stage1(dir / "none.json", 1280, 720), "none.json");
}

TEST(ReleasedStage1, AnnotationsRefuseTheStage1Layout) {
  TempDir dir;
  write_text(dir / "a.json", stage1("[[497.5, 283.25], [290.25, 29.5]]"));
  EXPECT_THROW_MSG(shle::load_labelme(dir / "a.json"), "read such files with --boxes released-stage1");
  shle::FrameFiles f;
  f.annotation = dir / "a.json";
  shle::AnnotationBoxSource src;
  EXPECT_THROW_MSG(src.candidates(shle::FrameContext{0, &f, nullptr}), "released stage-1 writer's layout");
  // The same points with LabelMe's keys are corners.
  write_text(dir / "b.json", stage1("[[497.5, 283.25], [790.25, 329.5]]", ", \"group_id\": null", ", \"imageData\": null"));
  shle::LabelmeFile lm = shle::load_labelme(dir / "b.json");
  ASSERT_EQ(lm.boxes.size(), 1u);
  EXPECT_EQ(lm.boxes[0].x1, 790.25);
}

// A two-frame released-layout sequence with images 1280x720 (sizes passed in).
struct TwoFrames {
  TempDir dir;
  shle::Sequence seq;
  std::vector<shle::ImageSize> sizes{{1280, 720}, {1280, 720}};
  TwoFrames() {
    write_text(dir / "s/left_colorimages/left_1_2_3_4.png", "x");
    write_text(dir / "s/left_colorimages/left_1_2_3_5.png", "x");
    seq = shle::scan_sequence(dir / "s");
  }
};

TEST(ReleasedStage1, SourceMapsFilesToFrames) {
  TwoFrames t;
  write_text(t.dir / "st/left_1_2_3_5.json", stage1("[[10, 20], [30, 40]]"));
  write_text(t.dir / "st/notes.txt", "ignored");
  shle::ReleasedStage1Source src(t.dir / "st", t.seq, t.sizes);
  EXPECT_EQ(src.files(), 1u);
  EXPECT_TRUE(src.candidates(shle::FrameContext{0, &t.seq.frames[0], nullptr}).empty());
  std::vector<shle::Candidate> c = src.candidates(shle::FrameContext{1, &t.seq.frames[1], nullptr});
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].box.x1, 40);
  EXPECT_EQ(c[0].box.y1, 60);
}

TEST(ReleasedStage1, SourceErrors) {
  TwoFrames t;
  EXPECT_THROW_MSG(shle::ReleasedStage1Source(t.dir / "none", t.seq, t.sizes), "no such folder");
  write_text(t.dir / "empty/readme.txt", "x");
  EXPECT_THROW_MSG(shle::ReleasedStage1Source(t.dir / "empty", t.seq, t.sizes), "no .json files");
  write_text(t.dir / "other/left_9_9_9_9.json", stage1("[[10, 20], [30, 40]]"));
  EXPECT_THROW_MSG(shle::ReleasedStage1Source(t.dir / "other", t.seq, t.sizes), "left_9_9_9_9.json: no image");
  write_text(t.dir / "bad/left_1_2_3_4.json", stage1("[[10, 20], [1300, 40]]"));
  EXPECT_THROW_MSG(shle::ReleasedStage1Source(t.dir / "bad", t.seq, t.sizes), "bad/left_1_2_3_4.json");
  // The bounds are the frame's own image size.
  write_text(t.dir / "small/left_1_2_3_4.json", stage1("[[10, 20], [700, 40]]"));
  std::vector<shle::ImageSize> small{{640, 480}, {1280, 720}};
  EXPECT_THROW_MSG(shle::ReleasedStage1Source(t.dir / "small", t.seq, small), "640x480");
  EXPECT_THROW_MSG(shle::ReleasedStage1Source(t.dir / "small", t.seq, {{1280, 720}}), "image sizes for 1 frames");
}

std::vector<shle::CocoDetection> coco(const std::string& text) {
  return shle::parse_coco_results(json::parse(text, "r.json"), "r.json");
}

TEST(CocoResults, Parses) {
  std::vector<shle::CocoDetection> d = coco(
      R"([{"image_id": 2, "category_id": 1, "bbox": [10.5, 20, 100, 30], "score": 0.9, "segmentation": []},
          {"image_id": 1, "category_id": 0, "bbox": [0, 0, 0, 0], "score": 0}])");
  ASSERT_EQ(d.size(), 2u);
  EXPECT_EQ(d[0].image_id, 2);
  EXPECT_EQ(d[0].box().x1, 110.5);
  EXPECT_EQ(d[0].box().y1, 50);
  EXPECT_EQ(d[0].score, 0.9);
  EXPECT_TRUE(coco("[]").empty());
}

TEST(CocoResults, Malformed) {
  auto bad = [](const std::string& text, const char* msg) { EXPECT_THROW_MSG(coco(text), msg); };
  const std::string ok_tail = R"(, "category_id": 1, "bbox": [1, 2, 3, 4], "score": 0.5})";
  bad("{}", "must be a JSON array");
  bad("[3]", "record 0 is not an object");
  bad(R"([{"category_id": 1, "bbox": [1, 2, 3, 4], "score": 0.5}])", "no integer \"image_id\"");
  bad("[{\"image_id\": 0" + ok_tail + "]", "\"image_id\" 0 is not an integer >= 1");
  bad("[{\"image_id\": 1.5" + ok_tail + "]", "\"image_id\" 1.5");
  bad(R"([{"image_id": 1, "bbox": [1, 2, 3, 4], "score": 0.5}])", "no integer \"category_id\"");
  bad(R"([{"image_id": 1, "category_id": 1, "score": 0.5}])", "\"bbox\" must be [x, y, w, h]");
  bad(R"([{"image_id": 1, "category_id": 1, "bbox": [1, 2, 3], "score": 0.5}])", "\"bbox\" must be [x, y, w, h]");
  bad(R"([{"image_id": 1, "category_id": 1, "bbox": [1, 2, 3, "4"], "score": 0.5}])", "not a finite number");
  bad(R"([{"image_id": 1, "category_id": 1, "bbox": [1, 2, 3, 1e400], "score": 0.5}])", "number is too large");
  bad(R"([{"image_id": 1, "category_id": 1, "bbox": [500, 300, 400, 280], "score": 0.5},
          {"image_id": 1, "category_id": 1, "bbox": [500, 300, 450, 250], "score": 1.5}])",
      "record 1: \"score\" 1.5 is not in [0, 1]");
  bad(R"([{"image_id": 1, "category_id": 1, "bbox": [500, 300, 100, -20], "score": 0.5}])", "negative width or height");
  bad(R"([{"image_id": 1, "category_id": 1, "bbox": [1, 2, 3, 4]}])", "\"score\" must be a finite number");
  TempDir dir;
  write_text(dir / "e.json", "");
  EXPECT_THROW_MSG(shle::load_coco_results(dir / "e.json"), "e.json: empty file");
  write_text(dir / "n.json", R"([{"image_id": 1, "category_id": 1, "bbox": [NaN, 2, 3, 4], "score": 0.5}])");
  EXPECT_THROW_MSG(shle::load_coco_results(dir / "n.json"), "n.json");
}

TEST(CocoResults, ImagesFile) {
  std::map<std::int64_t, std::string> m = shle::parse_coco_images(
      json::parse(R"({"images": [{"id": 2, "file_name": "/abs/x/left_1_2_3_5.png"}, {"id": 1, "file_name": "b.png"}]})",
                  "i"),
      "i.json");
  EXPECT_EQ(m.at(2), "left_1_2_3_5.png");
  EXPECT_EQ(m.at(1), "b.png");
  auto bad = [](const std::string& text, const char* msg) {
    EXPECT_THROW_MSG(shle::parse_coco_images(json::parse(text, "i.json"), "i.json"), msg);
  };
  bad("[]", "must be a JSON object");
  bad("{}", "no \"images\" array");
  bad(R"({"images": [1]})", "image 0 is not an object");
  bad(R"({"images": [{"file_name": "a.png"}]})", "no integer \"id\"");
  bad(R"({"images": [{"id": 1}]})", "no string \"file_name\"");
  bad(R"({"images": [{"id": 1, "file_name": "dir/"}]})", "has no file name");
  bad(R"({"images": [{"id": 1, "file_name": "a.png"}, {"id": 1, "file_name": "b.png"}]})", "id 1 appears twice");
}

TEST(CocoResults, SourceMapsIdsAndChecksBounds) {
  TwoFrames t;
  write_text(t.dir / "r.json", R"([{"image_id": 7, "category_id": 1, "bbox": [10, 20, 30, 40], "score": 0.8},
                                   {"image_id": 7, "category_id": 1, "bbox": [1, 2, 3, 4], "score": 0.2}])");
  write_text(t.dir / "i.json", R"({"images": [{"id": 7, "file_name": "/x/left_1_2_3_4.png"},
                                              {"id": 3, "file_name": "/x/left_1_2_3_5.png"}]})");
  shle::CocoResultsSource src(t.dir / "r.json", t.dir / "i.json", t.seq, t.sizes);
  EXPECT_EQ(src.records(), 2u);
  std::vector<shle::Candidate> c = src.candidates(shle::FrameContext{0, &t.seq.frames[0], nullptr});
  ASSERT_EQ(c.size(), 2u);  // file order, every score (the box rule applies the threshold)
  EXPECT_EQ(c[0].box.x1, 40);
  EXPECT_EQ(c[1].score, 0.2);
  EXPECT_TRUE(src.candidates(shle::FrameContext{1, &t.seq.frames[1], nullptr}).empty());
  // Ids without a listing only with the explicit "sorted".
  EXPECT_THROW_MSG(shle::CocoResultsSource(t.dir / "r.json", "", t.seq, t.sizes), "need the dataset file");
  EXPECT_THROW_MSG(shle::CocoResultsSource(t.dir / "r.json", "sorted", t.seq, t.sizes),
                   "image_id 7 but the sequence has 2 images");
  write_text(t.dir / "r2.json", R"([{"image_id": 2, "category_id": 1, "bbox": [10, 20, 30, 40], "score": 0.8}])");
  shle::CocoResultsSource sorted(t.dir / "r2.json", "sorted", t.seq, t.sizes);
  EXPECT_EQ(sorted.candidates(shle::FrameContext{1, &t.seq.frames[1], nullptr}).size(), 1u);
  EXPECT_THROW_MSG(shle::CocoResultsSource(t.dir / "r2.json", t.dir / "i.json", t.seq, t.sizes),
                   "image_id 2 is not in");
  write_text(t.dir / "i2.json", R"({"images": [{"id": 2, "file_name": "other.png"}]})");
  EXPECT_THROW_MSG(shle::CocoResultsSource(t.dir / "r2.json", t.dir / "i2.json", t.seq, t.sizes),
                   "image 'other.png' (id 2) is not in");
  // Boxes outside the image (detectron2 clips to it): a wrong file or sequence.
  write_text(t.dir / "r3.json", R"([{"image_id": 1, "category_id": 1, "bbox": [1000, 20, 300, 40], "score": 0.8}])");
  EXPECT_THROW_MSG(shle::CocoResultsSource(t.dir / "r3.json", "sorted", t.seq, t.sizes),
                   "r3.json: record 0: bbox reaches outside the 1280x720 image left_1_2_3_4.png");
  write_text(t.dir / "r4.json", R"([{"image_id": 1, "category_id": 1, "bbox": [-3, 20, 30, 40], "score": 0.8}])");
  EXPECT_THROW_MSG(shle::CocoResultsSource(t.dir / "r4.json", "sorted", t.seq, t.sizes), "outside");
  EXPECT_THROW_MSG(shle::CocoResultsSource(t.dir / "missing.json", "sorted", t.seq, t.sizes), "missing.json");
}

TEST(ReleasedGate, IouAndDistanceRule) {
  // The released IoU: truncated corners, inclusive +1.
  EXPECT_DOUBLE_EQ(shle::released_iou({0, 0, 9, 9}, {0, 0, 9, 9}), 1.0);
  EXPECT_DOUBLE_EQ(shle::released_iou({0, 0, 9.9, 9.9}, {5, 0, 14, 9}), 50.0 / 150.0);
  // Touching edges overlap by one pixel column under +1.
  EXPECT_GT(shle::released_iou({0, 0, 10, 10}, {10, 0, 20, 10}), 0.0);
  EXPECT_EQ(shle::released_iou({0, 0, 10, 10}, {11, 0, 20, 10}), 0.0);
  EXPECT_EQ(shle::released_iou({0, 0, -1, -1}, {0, 0, -1, -1}), 0.0);  // zero denominator
  const shle::Box gt{500, 280, 800, 320};
  EXPECT_TRUE(shle::released_gate({510, 290, 790, 310}, gt));
  // No overlap, right edge 150 px from the annotation's left edge, top 10 px off: kept.
  EXPECT_TRUE(shle::released_gate({100, 290, 350, 330}, gt));
  // The same box 25 px lower: refused (col_dis >= 20).
  EXPECT_FALSE(shle::released_gate({100, 305, 350, 345}, gt));
  // Right edge exactly 200 px away: refused (strict <).
  EXPECT_FALSE(shle::released_gate({100, 290, 300, 330}, gt));
  // The released rule compares the predicted RIGHT edge with the annotation's LEFT
  // edge: a box left of the device ending near it is kept, one right of it is not.
  EXPECT_FALSE(shle::released_gate({1000, 285, 1270, 315}, gt));
  EXPECT_FALSE(shle::released_gate({20, 600, 1220, 710}, gt));
}

TEST(ReleasedGate, StreamRefusesIt) {
  shle::PipelineOptions o;
  o.gate_with_annotations = true;
  EXPECT_THROW_MSG(shle::StreamEstimator(shle::Calibration{}, o), "gate_with_annotations needs the LabelMe annotations");
}

TEST(DisparityHeight, ScansScenes) {
  TempDir dir;
  write_text(dir / "adas_params/calibData.json", "{}");
  write_text(dir / "val/images_019/left_colorimages/a.png", "x");
  write_text(dir / "val/images_017/left_colorimages/a.png", "x");
  write_text(dir / "val/images_018/other.txt", "x");  // no left_colorimages: not a scene
  write_text(dir / "val/notes/x.txt", "x");
  shle::DisparityHeightDataset d = shle::scan_disparity_height(dir.path());
  ASSERT_EQ(d.scenes.size(), 2u);
  EXPECT_EQ(d.scenes[0].id, 17);
  EXPECT_EQ(d.scenes[0].name, "images_017");
  EXPECT_EQ(d.scenes[1].id, 19);
  write_text(dir / "val/images_17/left_colorimages/a.png", "x");
  EXPECT_THROW_MSG(shle::scan_disparity_height(dir.path()), "scene 17 again");
  TempDir empty;
  EXPECT_THROW_MSG(shle::scan_disparity_height(empty / "none"), "no such dataset folder");
  EXPECT_THROW_MSG(shle::scan_disparity_height(empty.path()), "val: no such folder");
  write_text(empty / "val/x.txt", "x");
  EXPECT_THROW_MSG(shle::scan_disparity_height(empty.path()), "adas_params: no such folder");
  write_text(empty / "adas_params/calibData.json", "{}");
  EXPECT_THROW_MSG(shle::scan_disparity_height(empty.path()), "no scene folders");
}

TEST(DisparityHeight, GroundTruthTable) {
  EXPECT_EQ(shle::released_gt_heights().at(17), 2.85);
  EXPECT_EQ(shle::released_gt_heights().at(18), 2.2);
  EXPECT_EQ(shle::released_gt_heights().at(19), 5.3);
  std::map<int, double> t =
      shle::parse_gt_heights("scene,height\r\n# the paper's test scenes\n17, 2.85\nimages_018,2.2\n\n019,5.3e0\n", "g.csv");
  EXPECT_EQ(t.size(), 3u);
  EXPECT_EQ(t.at(18), 2.2);
  EXPECT_EQ(t.at(19), 5.3);
  EXPECT_EQ(shle::parse_scene_id("images_007"), 7);
  EXPECT_EQ(shle::parse_scene_id("images_"), -1);
  EXPECT_EQ(shle::parse_scene_id("0"), -1);
  EXPECT_EQ(shle::parse_scene_id("1234567"), -1);
  auto bad = [](const std::string& text, const char* msg) { EXPECT_THROW_MSG(shle::parse_gt_heights(text, "g.csv"), msg); };
  bad("", "g.csv: no scene,height line");
  bad("scene,height\n# nothing\n", "no scene,height line");
  bad("17\n", "line 1: expected scene,height");
  bad("17,2.85,3\n", "line 1: expected scene,height");
  bad("x17,2.85\n", "scene 'x17' is not a scene number");
  bad("17,nan\n", "height 'nan' is not a number of metres");
  bad("17,inf\n", "height 'inf'");
  bad("17,-2\n", "height '-2'");
  bad("17,0\n", "height '0'");
  bad("17,1e3\n", "height '1e3'");
  bad("17,\n", "height ''");
  bad("17,2.85\n017,2.9\n", "line 2: scene 17 is listed twice");
  bad("17,2.85\nscene,height\n", "line 2: scene 'scene'");
  TempDir dir;
  write_text(dir / "g.csv", "15,2.85\n");
  EXPECT_EQ(shle::load_gt_heights(dir / "g.csv").at(15), 2.85);
  write_text(dir / "e.csv", "");
  EXPECT_THROW_MSG(shle::load_gt_heights(dir / "e.csv"), "e.csv: no scene,height line");
  EXPECT_THROW_MSG(shle::load_gt_heights(dir / "none.csv"), "none.csv");

  std::map<int, double> m = shle::released_gt_heights();
  shle::parse_gt_height_args("17=3.0, images_015=2.85", &m);
  EXPECT_EQ(m.at(17), 3.0);
  EXPECT_EQ(m.at(15), 2.85);
  EXPECT_THROW_MSG(shle::parse_gt_height_args("17", &m), "expected SCENE=METRES");
  EXPECT_THROW_MSG(shle::parse_gt_height_args("a=2", &m), "the scene is not a number");
  EXPECT_THROW_MSG(shle::parse_gt_height_args("17=NaN", &m), "the height is not a number");
  EXPECT_THROW_MSG(shle::parse_gt_height_args("17=2,", &m), "expected SCENE=METRES");
}

}  // namespace
