// The released "Disparity Height" dataset as a whole (shle.md section 2):
//   ROOT/adas_params/calibData.json, DepthCalib.json     SmarterEye calibration
//   ROOT/val/images_0XX/left_colorimages/*.png, *.json    left images, LabelMe
//   ROOT/val/images_0XX/disparity_images/disparity_5_*.dat
// (ROOT is the released data/demo_data), and the per-scene ground-truth heights
// the released Stage2/post_process.py hard-codes.
#pragma once

#include <map>
#include <string>
#include <string_view>
#include <vector>

namespace shle {

struct DisparityHeightScene {
  int id = 0;        // 17 for images_017
  std::string name;  // "images_017"
  std::string dir;   // ROOT/val/images_017
};

struct DisparityHeightDataset {
  std::string root, adas_params;
  std::vector<DisparityHeightScene> scenes;  // by id
};

// Every folder ROOT/val/images_<digits> that holds left_colorimages/, by scene id.
// Throws shle::Error when ROOT/val or ROOT/adas_params is missing, no scene is
// found, or two folders have the same id (images_17 and images_017).
DisparityHeightDataset scan_disparity_height(const std::string& root);

// "17", "017" or "images_017" -> 17; -1 unless 1..999999.
int parse_scene_id(std::string_view token);

// Scene id -> ground-truth height (m): the released code's active table,
// 17 -> 2.85, 18 -> 2.2, 19 -> 5.3.
std::map<int, double> released_gt_heights();

// A ground-truth table, one "scene,height" per line (scene as parse_scene_id
// reads it, height in metres, finite, 0 < h <= 100); an optional header line
// "scene,height", blank lines and '#' comments are ignored; CRLF accepted.
// Errors: shle::Error "<source>: line N: <problem>" (also for a scene listed
// twice and for a file without any entry).
std::map<int, double> parse_gt_heights(std::string_view text, const std::string& source);
std::map<int, double> load_gt_heights(const std::string& path);

// "17=2.85" (several separated by commas) into `table`, replacing entries.
// Throws shle::Error naming the bad item.
void parse_gt_height_args(std::string_view text, std::map<int, double>* table);

}  // namespace shle
