// The box files the released SHLE stage 1 leaves behind (github.com/Yang-Kaixing/SHLE,
// Stage1/tracking_faster_rcnn.py, commit 4a941c3), and detectron2's
// coco_instances_results.json that stage 1 reads:
//
//   * stage-1 box file, one per frame, named <image name up to its first '.'>.json:
//     a LabelMe-shaped object whose single shape ("label": "height") has
//     "points": [[x, y], [w, h]] -- the top-left corner and the SIZE, not two corners;
//   * coco_instances_results.json: [{"image_id", "category_id", "bbox": [x, y, w, h],
//     "score"}, ...];
//   * the COCO dataset file the detector ran on (test2017_images_0XX.json):
//     {"images": [{"id", "file_name"}, ...], ...}, which maps image_id to a file.
//
// The two stage-1 forms (size vs corners) are both valid JSON of the same shape, so
// the readers check what the chosen form implies and refuse a file that does not fit
// (see docs/SHLE.md, "Released box files"). Parsers take json::Value (weights/json.h)
// and throw shle::Error "<source>: <problem>".
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "shle/types.h"

namespace json {
class Value;
}

namespace shle {

// How far (px) a released box may reach beyond the image: detectron2 clips its boxes
// to the image and MIL keeps its windows inside, so only float32 rounding of
// x + w (about 1e-4 px at 1280) can exceed it. One pixel is generous for that and
// still refuses corner-form files read as sizes, whose "x + w" is x0 + x1.
constexpr double kReleasedBoxSlack = 1.0;

// A released stage-1 file as corners [x, y, x + w, y + h]. Strict: no "imageData"
// key and no shape with "group_id" (the LabelMe tool always writes both, the
// released stage-1 writer never: such a file holds corners); exactly one
// shape, labelled "height", with exactly two finite [number, number] points; the
// second point is a size, so w >= 0 and h >= 0; and the box lies in the
// width x height image (within kReleasedBoxSlack). `imageWidth` / `imageHeight`,
// when present, must be integers in 1..65535 (the released writer always writes
// 1280 x 720; the bounds come from the actual image).
Box parse_released_stage1(const json::Value& root, const std::string& source, int width, int height);
Box load_released_stage1(const std::string& path, int width, int height);

// True when `root` has exactly the key set the released stage-1 writer produces
// (top level: version, flags, shapes, imagePath, imageHeight, imageWidth; each
// shape: label, points, shape_type, flags) -- no "imageData" and no "group_id",
// which the LabelMe tool always writes. Used to refuse such a file where LabelMe
// corners are expected.
bool has_released_stage1_layout(const json::Value& root);

struct CocoDetection {
  std::int64_t image_id = 0;
  std::int64_t category_id = 0;
  double x = 0, y = 0, w = 0, h = 0;  // bbox as written: top-left and size
  double score = 0;
  Box box() const { return Box{x, y, x + w, y + h}; }
};

// Strict: a JSON array (possibly empty) of objects with an integer "image_id" >= 1,
// an integer "category_id", "bbox" of four finite numbers with w >= 0 and h >= 0,
// and a finite "score" in [0, 1]; other keys (e.g. "segmentation") are ignored.
// File order is kept (the released widest rule keeps the first of equal widths).
std::vector<CocoDetection> parse_coco_results(const json::Value& root, const std::string& source);
std::vector<CocoDetection> load_coco_results(const std::string& path);

// The "images" of a COCO dataset file: id -> base name of "file_name" (the part
// after the last '/'). Ids must be unique integers >= 1, names non-empty strings.
std::map<std::int64_t, std::string> parse_coco_images(const json::Value& root, const std::string& source);
std::map<std::int64_t, std::string> load_coco_images(const std::string& path);

// Reads a JSON file with a size limit (64 MiB); errors name the file.
json::Value load_json_file(const std::string& path);

}  // namespace shle
