#include "shle/labelme.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "shle/error.h"
#include "shle/released_boxes.h"
#include "weights/json.h"

namespace shle {
namespace {

std::string num(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

}  // namespace

LabelmeFile parse_labelme(const json::Value& root, const std::string& source, const std::string& label) {
  if (!root.is_object()) throw Error(source + ": LabelMe file must be a JSON object");
  LabelmeFile f;
  auto dim = [&](const char* key) {
    const json::Value* v = root.get(key);
    if (!v || v->is_null()) return 0;
    if (!v->is_number() || v->number() != std::floor(v->number()) || v->number() < 1 || v->number() > 65535)
      throw Error(source + ": '" + key + "' must be an integer in 1..65535");
    return static_cast<int>(v->number());
  };
  f.image_width = dim("imageWidth");
  f.image_height = dim("imageHeight");
  const json::Value* shapes = root.get("shapes");
  if (!shapes || !shapes->is_array()) throw Error(source + ": no \"shapes\" array");
  std::size_t index = 0;
  for (const json::Value& s : shapes->array()) {
    std::string where = source + ": shape " + std::to_string(index++);
    if (!s.is_object()) throw Error(where + " is not an object");
    const json::Value* l = s.get("label");
    if (!l || !l->is_string()) throw Error(where + " has no string \"label\"");
    const json::Value* pts = s.get("points");
    if (!pts || !pts->is_array()) throw Error(where + " has no \"points\" array");
    if (l->str() != label) continue;
    if (pts->array().size() < 2) throw Error(where + " has fewer than 2 points");
    Box b{INFINITY, INFINITY, -INFINITY, -INFINITY};
    for (const json::Value& p : pts->array()) {
      if (!p.is_array() || p.array().size() != 2 || !p.array()[0].is_number() || !p.array()[1].is_number())
        throw Error(where + ": a point is not an [x, y] pair of numbers");
      double x = p.array()[0].number(), y = p.array()[1].number();
      if (!std::isfinite(x) || !std::isfinite(y)) throw Error(where + ": a point is not finite");
      b.x0 = std::min(b.x0, x);
      b.y0 = std::min(b.y0, y);
      b.x1 = std::max(b.x1, x);
      b.y1 = std::max(b.y1, y);
    }
    f.boxes.push_back(b);
  }
  return f;
}

LabelmeFile load_labelme(const std::string& path, const std::string& label) {
  json::Value root;
  try {
    root = json::parse_file(path);
  } catch (const json::Error& e) {
    throw Error(e.what());
  }
  // Same JSON shape, different meaning: never read [[x, y], [w, h]] as corners.
  if (has_released_stage1_layout(root))
    throw Error(path + ": has the released stage-1 writer's layout (points [[x, y], [w, h]], no imageData, no "
                "group_id); read such files with --boxes released-stage1 DIR");
  return parse_labelme(root, path, label);
}

std::string labelme_json(const std::string& image_name, int width, int height, const std::vector<Box>& boxes,
                         const std::string& label) {
  std::string s = "{\n  \"version\": \"5.0.1\",\n  \"flags\": {},\n  \"shapes\": [";
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    const Box& b = boxes[i];
    s += i ? ",\n" : "\n";
    s += "    {\"label\": " + json::quote(label) + ", \"points\": [[" + num(b.x0) + ", " + num(b.y0) + "], [" +
         num(b.x1) + ", " + num(b.y1) + "]], \"group_id\": null, \"shape_type\": \"rectangle\", \"flags\": {}}";
  }
  s += boxes.empty() ? "],\n" : "\n  ],\n";
  s += "  \"imagePath\": " + json::quote(image_name) + ",\n  \"imageData\": null,\n";
  s += "  \"imageHeight\": " + std::to_string(height) + ",\n  \"imageWidth\": " + std::to_string(width) + "\n}\n";
  return s;
}

}  // namespace shle
