#include "shle/released_boxes.h"

#include <cmath>
#include <cstdio>
#include <set>
#include <string_view>

#include "shle/error.h"
#include "shle/file_read.h"
#include "weights/json.h"
#include "weights/quote_name.h"

namespace shle {
namespace {

std::string fmt(double v) {
  char b[64];
  std::snprintf(b, sizeof b, "%.10g", v);
  return b;
}

// A finite JSON number, or throws "<where> <what> must be a finite number".
double finite_number(const json::Value* v, const std::string& where, const char* what) {
  if (!v || !v->is_number() || !std::isfinite(v->number()))
    throw Error(where + ": \"" + what + "\" must be a finite number");
  return v->number();
}

// An integer-valued JSON number in [lo, 2^53].
std::int64_t integer(const json::Value* v, const std::string& where, const char* what, double lo) {
  if (!v || !v->is_number()) throw Error(where + ": no integer \"" + what + "\"");
  const double d = v->number();
  if (!std::isfinite(d) || d != std::floor(d) || d < lo || d > 9007199254740992.0)
    throw Error(where + ": \"" + what + "\" " + fmt(d) + " is not an integer >= " + fmt(lo));
  return static_cast<std::int64_t>(d);
}

bool keys_are(const json::Value& obj, std::initializer_list<std::string_view> keys) {
  if (!obj.is_object() || obj.object().size() != keys.size()) return false;
  for (std::string_view k : keys)
    if (!obj.get(k)) return false;
  return true;
}

}  // namespace

json::Value load_json_file(const std::string& path) {
  std::vector<std::uint8_t> bytes = read_file_bytes(path, 64ull << 20);
  if (bytes.empty()) throw Error(path + ": empty file (expected JSON)");
  try {
    return json::parse(std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()), path);
  } catch (const json::Error& e) {
    throw Error(e.what());
  }
}

Box parse_released_stage1(const json::Value& root, const std::string& source, int width, int height) {
  if (!root.is_object()) throw Error(source + ": a released stage-1 box file must be a JSON object");
  for (const char* key : {"imageWidth", "imageHeight"}) {
    const json::Value* v = root.get(key);
    if (v && !v->is_null() && integer(v, source, key, 1) > 65535)
      throw Error(source + ": \"" + key + "\" is beyond 65535");
  }
  const json::Value* shapes = root.get("shapes");
  if (!shapes || !shapes->is_array()) throw Error(source + ": no \"shapes\" array");
  // The LabelMe tool always writes these keys, the released stage-1 writer never:
  // such a file holds corners, whatever its geometry would allow.
  bool labelme_keys = root.get("imageData") != nullptr;
  for (const json::Value& s : shapes->array()) labelme_keys = labelme_keys || (s.is_object() && s.get("group_id"));
  if (labelme_keys)
    throw Error(source + ": written by LabelMe (has imageData / group_id, which the released stage 1 never "
                "writes), so its points are corners: read it with --boxes annotations");
  if (shapes->array().size() != 1)
    throw Error(source + ": " + std::to_string(shapes->array().size()) +
                " shapes; the released stage 1 writes exactly one box per file");
  const json::Value& s = shapes->array()[0];
  const std::string where = source + ": shape 0";
  if (!s.is_object()) throw Error(where + " is not an object");
  const json::Value* label = s.get("label");
  if (!label || !label->is_string()) throw Error(where + " has no string \"label\"");
  if (label->str() != "height")
    throw Error(where + " is labelled " + weights::quote_name(label->str()) + "; the released stage 1 writes \"height\"");
  const json::Value* pts = s.get("points");
  if (!pts || !pts->is_array()) throw Error(where + " has no \"points\" array");
  if (pts->array().size() != 2)
    throw Error(where + " has " + std::to_string(pts->array().size()) +
                " points; a released stage-1 box is [[x, y], [w, h]]");
  double v[4];
  for (int i = 0; i < 2; ++i) {
    const json::Value& p = pts->array()[i];
    if (!p.is_array() || p.array().size() != 2 || !p.array()[0].is_number() || !p.array()[1].is_number())
      throw Error(where + ": point " + std::to_string(i) + " is not a pair of numbers");
    v[2 * i] = p.array()[0].number();
    v[2 * i + 1] = p.array()[1].number();
    if (!std::isfinite(v[2 * i]) || !std::isfinite(v[2 * i + 1]))
      throw Error(where + ": point " + std::to_string(i) + " is not finite");
  }
  const double x = v[0], y = v[1], w = v[2], h = v[3];
  const std::string form = "[[x, y], [w, h]] = [[" + fmt(x) + ", " + fmt(y) + "], [" + fmt(w) + ", " + fmt(h) + "]]";
  const char* hint = " (is this a LabelMe corner file? read those with --boxes annotations)";
  if (w < 0 || h < 0) throw Error(source + ": " + form + " has a negative size" + hint);
  if (x < -kReleasedBoxSlack || y < -kReleasedBoxSlack)
    throw Error(source + ": " + form + " starts outside the image");
  if (x + w > width + kReleasedBoxSlack || y + h > height + kReleasedBoxSlack)
    throw Error(source + ": " + form + " ends at (x + w, y + h) = (" + fmt(x + w) + ", " + fmt(y + h) +
                "), outside the " + std::to_string(width) + "x" + std::to_string(height) + " image" + hint);
  return Box{x, y, x + w, y + h};
}

Box load_released_stage1(const std::string& path, int width, int height) {
  return parse_released_stage1(load_json_file(path), path, width, height);
}

bool has_released_stage1_layout(const json::Value& root) {
  if (!keys_are(root, {"version", "flags", "shapes", "imagePath", "imageHeight", "imageWidth"})) return false;
  const json::Value* shapes = root.get("shapes");
  if (!shapes->is_array() || shapes->array().empty()) return false;
  for (const json::Value& s : shapes->array())
    if (!keys_are(s, {"label", "points", "shape_type", "flags"})) return false;
  return true;
}

std::vector<CocoDetection> parse_coco_results(const json::Value& root, const std::string& source) {
  if (!root.is_array())
    throw Error(source + ": COCO results must be a JSON array of {image_id, category_id, bbox, score}");
  std::vector<CocoDetection> out;
  out.reserve(root.array().size());
  std::size_t index = 0;
  for (const json::Value& r : root.array()) {
    const std::string where = source + ": record " + std::to_string(index++);
    if (!r.is_object()) throw Error(where + " is not an object");
    CocoDetection d;
    d.image_id = integer(r.get("image_id"), where, "image_id", 1);
    d.category_id = integer(r.get("category_id"), where, "category_id", -9007199254740992.0);
    const json::Value* bbox = r.get("bbox");
    if (!bbox || !bbox->is_array() || bbox->array().size() != 4)
      throw Error(where + ": \"bbox\" must be [x, y, w, h]");
    double b[4];
    for (int i = 0; i < 4; ++i) {
      const json::Value& e = bbox->array()[i];
      if (!e.is_number() || !std::isfinite(e.number()))
        throw Error(where + ": \"bbox\" [x, y, w, h] holds a value that is not a finite number");
      b[i] = e.number();
    }
    if (b[2] < 0 || b[3] < 0)
      throw Error(where + ": \"bbox\" [" + fmt(b[0]) + ", " + fmt(b[1]) + ", " + fmt(b[2]) + ", " + fmt(b[3]) +
                  "] has a negative width or height (COCO boxes are [x, y, w, h], not corners)");
    d.x = b[0], d.y = b[1], d.w = b[2], d.h = b[3];
    d.score = finite_number(r.get("score"), where, "score");
    if (d.score < 0 || d.score > 1) throw Error(where + ": \"score\" " + fmt(d.score) + " is not in [0, 1]");
    out.push_back(d);
  }
  return out;
}

std::vector<CocoDetection> load_coco_results(const std::string& path) {
  return parse_coco_results(load_json_file(path), path);
}

std::map<std::int64_t, std::string> parse_coco_images(const json::Value& root, const std::string& source) {
  if (!root.is_object()) throw Error(source + ": a COCO dataset file must be a JSON object");
  const json::Value* images = root.get("images");
  if (!images || !images->is_array()) throw Error(source + ": no \"images\" array");
  std::map<std::int64_t, std::string> out;
  std::size_t index = 0;
  for (const json::Value& im : images->array()) {
    const std::string where = source + ": image " + std::to_string(index++);
    if (!im.is_object()) throw Error(where + " is not an object");
    std::int64_t id = integer(im.get("id"), where, "id", 1);
    const json::Value* name = im.get("file_name");
    if (!name || !name->is_string()) throw Error(where + " has no string \"file_name\"");
    std::string base = name->str().substr(name->str().rfind('/') + 1);
    if (base.empty()) throw Error(where + ": \"file_name\" has no file name");
    if (!out.emplace(id, base).second) throw Error(where + ": id " + std::to_string(id) + " appears twice");
  }
  return out;
}

std::map<std::int64_t, std::string> load_coco_images(const std::string& path) {
  return parse_coco_images(load_json_file(path), path);
}

}  // namespace shle
