#include "apps/stixelnext/calibration.h"

#include "weights/quote_name.h"

#include <cmath>
#include <stdexcept>

#include "weights/json.h"

namespace stixelnext {

namespace {

std::vector<float> numbers(const json::Value& doc, const char* key, std::size_t count, const std::string& path) {
  const json::Value* v = doc.get(key);
  if (!v->is_array())
    throw std::runtime_error(path + ": \"" + key + "\" must be an array of " + std::to_string(count) + " numbers");
  if (v->array().size() != count)
    throw std::runtime_error(path + ": \"" + key + "\" has " + std::to_string(v->array().size()) +
                             " values, expected " + std::to_string(count) + " (row-major)");
  std::vector<float> out;
  for (const auto& x : v->array()) {
    // The camera model is float32: 1e300 is finite as a double but Inf as a float.
    if (!x.is_number() || !std::isfinite(static_cast<float>(x.number())))
      throw std::runtime_error(path + ": \"" + key + "\" holds a value that is not a finite float32 number");
    out.push_back(static_cast<float>(x.number()));
  }
  return out;
}

int positive_int(const json::Value& doc, const char* key, const std::string& path) {
  const json::Value* v = doc.get(key);
  if (!v) throw std::runtime_error(path + ": missing \"" + key + "\" (image size in pixels)");
  if (!v->is_number() || v->number() != std::floor(v->number()) || v->number() < 1 || v->number() > 100000)
    throw std::runtime_error(path + ": \"" + key + "\" must be a positive integer");
  return static_cast<int>(v->number());
}

// One of the authors' four scalars: a JSON number, finite as a float32.
float scalar(const json::Value& doc, const char* key, const std::string& path) {
  const json::Value* v = doc.get(key);
  if (!v) throw std::runtime_error(path + ": missing \"" + key + "\" (the authors' form needs fx, fy, cx and cy)");
  if (!v->is_number()) throw std::runtime_error(path + ": \"" + key + "\" must be a number");
  if (!std::isfinite(static_cast<float>(v->number())))
    throw std::runtime_error(path + ": \"" + key + "\" is not a finite float32 number");
  return static_cast<float>(v->number());
}

// StixelNExT_Pro's per-image {"fx", "fy", "cx", "cy"}.
Calibration parse_authors_form(const json::Value& doc, const std::string& path) {
  Calibration c;
  const float fx = scalar(doc, "fx", path), fy = scalar(doc, "fy", path);
  const float cx = scalar(doc, "cx", path), cy = scalar(doc, "cy", path);
  if (!(fx > 0) || !(fy > 0))
    throw std::runtime_error(path + ": focal lengths must be positive, got fx " + std::to_string(fx) + ", fy " +
                             std::to_string(fy));
  c.K = {fx, 0, cx, 0, fy, cy, 0, 0, 1};
  c.T = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  return c;
}

}  // namespace

Calibration read_calibration(const std::string& path) {
  json::Value doc;
  try {
    doc = json::parse_file(path);
  } catch (const json::Error& e) {
    throw std::runtime_error(e.what());
  }
  return parse_calibration(doc, path);
}

Calibration parse_calibration(const json::Value& doc, const std::string& path) {
  if (!doc.is_object())
    throw std::runtime_error(path + ": expected a JSON object with K, T, width, height (or fx, fy, cx, cy)");
  for (const char* key : {"fx", "fy", "cx", "cy"})
    if (doc.get(key)) return parse_authors_form(doc, path);
  for (const auto& [key, value] : doc.object()) {
    (void)value;
    if (key != "K" && key != "T" && key != "width" && key != "height")
      throw std::runtime_error(path + ": unknown key " + weights::quote_name(key) +
                               " (expected K, T, width, height, or the authors' fx, fy, cx, cy)");
  }
  Calibration c;
  if (!doc.get("K")) throw std::runtime_error(path + ": missing \"K\" (9 numbers, row-major)");
  c.K = numbers(doc, "K", 9, path);
  if (doc.get("T"))
    c.T = numbers(doc, "T", 16, path);
  else
    c.T = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  c.width = positive_int(doc, "width", path);
  c.height = positive_int(doc, "height", path);
  return c;
}

std::string per_image_calibration_path(const std::string& image_path) {
  const std::size_t slash = image_path.find_last_of('/');
  const std::string folder = slash == std::string::npos ? "" : image_path.substr(0, slash + 1);
  std::string name = slash == std::string::npos ? image_path : image_path.substr(slash + 1);
  const std::size_t dot = name.find_last_of('.');
  if (dot != std::string::npos && dot != 0) name = name.substr(0, dot);
  return folder + name + ".json";
}

}  // namespace stixelnext
