// LabelMe annotation files as the "Disparity Height" dataset uses them: a JSON
// object with "shapes": [{"label": "height", "points": [[x0, y0], [x1, y1]],
// "shape_type": "rectangle"}, ...], plus imageWidth / imageHeight.
#pragma once

#include <string>
#include <vector>

#include "shle/types.h"

namespace json {
class Value;
}

namespace shle {

struct LabelmeFile {
  int image_width = 0, image_height = 0;  // 0 when absent
  // Boxes of the shapes labelled `label`, in file order: the bounding box of each
  // shape's points (corners normalised so x0 <= x1, y0 <= y1).
  std::vector<Box> boxes;
};

// Strict: "shapes" must be an array of objects with a string "label" and "points"
// holding >= 2 finite [x, y] pairs; other keys are ignored. Throws shle::Error
// "<source>: <problem>".
LabelmeFile parse_labelme(const json::Value& root, const std::string& source,
                          const std::string& label = "height");
// Also refuses a file with the released stage-1 writer's exact layout
// (has_released_stage1_layout in released_boxes.h): its points are [x, y], [w, h],
// and reading them as corners gives wrong boxes without a word.
LabelmeFile load_labelme(const std::string& path, const std::string& label = "height");

// A LabelMe file with one rectangle per box (used by the synthetic generator).
std::string labelme_json(const std::string& image_name, int width, int height,
                         const std::vector<Box>& boxes, const std::string& label = "height");

}  // namespace shle
