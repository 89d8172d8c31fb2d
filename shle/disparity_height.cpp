#include "shle/disparity_height.h"

#include <cmath>
#include <cstdlib>
#include <filesystem>

#include "shle/error.h"
#include "shle/file_read.h"
#include "shle/text_fields.h"
#include "weights/quote_name.h"

namespace shle {
namespace {

namespace fs = std::filesystem;

// A plain decimal height in (0, 100] m, or false.
bool parse_height(std::string_view t, double* out) {
  double v = 0;
  if (t.size() > 32 || !parse_decimal(t, &v) || !(v > 0) || v > 100) return false;
  *out = v;
  return true;
}

std::string quoted(std::string_view s) { return weights::quote_name(std::string(s)); }

}  // namespace

int parse_scene_id(std::string_view t) {
  if (t.size() > 7 && t.substr(0, 7) == "images_") t.remove_prefix(7);
  if (t.empty() || t.size() > 6) return -1;
  int v = 0;
  for (char c : t) {
    if (c < '0' || c > '9') return -1;
    v = v * 10 + (c - '0');
  }
  return v >= 1 ? v : -1;
}

DisparityHeightDataset scan_disparity_height(const std::string& root) {
  std::error_code ec;
  const fs::path r(root), val = fs::path(root) / "val", adas = fs::path(root) / "adas_params";
  if (!fs::is_directory(r, ec)) throw Error(root + ": no such dataset folder");
  if (!fs::is_directory(val, ec))
    throw Error(val.string() + ": no such folder (a Disparity Height root holds val/images_0XX/ and adas_params/)");
  if (!fs::is_directory(adas, ec)) throw Error(adas.string() + ": no such folder (calibData.json, DepthCalib.json)");
  DisparityHeightDataset d;
  d.root = root;
  d.adas_params = adas.string();
  std::map<int, DisparityHeightScene> by_id;
  fs::directory_iterator it(val, ec), end;
  if (ec) throw Error(val.string() + ": cannot list (" + ec.message() + ")");
  for (; it != end; it.increment(ec)) {
    if (ec) throw Error(val.string() + ": cannot list (" + ec.message() + ")");
    const std::string name = it->path().filename().string();
    if (name.compare(0, 7, "images_") != 0) continue;
    const int id = parse_scene_id(name);
    std::error_code e2;
    if (id < 0 || !fs::is_directory(it->path() / "left_colorimages", e2)) continue;
    DisparityHeightScene s{id, name, it->path().string()};
    auto ins = by_id.emplace(id, s);
    if (!ins.second) throw Error(s.dir + ": scene " + std::to_string(id) + " again (also " + ins.first->second.dir + ")");
  }
  for (auto& [id, s] : by_id) d.scenes.push_back(s);
  if (d.scenes.empty()) throw Error(val.string() + ": no scene folders images_0XX/ with left_colorimages/");
  return d;
}

std::map<int, double> released_gt_heights() { return {{17, 2.85}, {18, 2.2}, {19, 5.3}}; }

std::map<int, double> parse_gt_heights(std::string_view text, const std::string& source) {
  std::map<int, double> out;
  std::size_t pos = 0, line_no = 0;
  bool first = true;
  while (pos < text.size()) {
    const std::string_view line = next_line(text, &pos);
    ++line_no;
    std::string_view t = trim_field(line);
    if (t.empty() || t.front() == '#') continue;
    const std::string where = source + ": line " + std::to_string(line_no) + ": ";
    std::size_t comma = t.find(',');
    if (comma == std::string_view::npos || t.find(',', comma + 1) != std::string_view::npos)
      throw Error(where + "expected scene,height");
    std::string_view a = trim_field(t.substr(0, comma)), b = trim_field(t.substr(comma + 1));
    if (first && a == "scene") {
      first = false;
      continue;
    }
    first = false;
    const int id = parse_scene_id(a);
    if (id < 0) throw Error(where + "scene " + quoted(a) + " is not a scene number (17, 017 or images_017)");
    double h = 0;
    if (!parse_height(b, &h)) throw Error(where + "height " + quoted(b) + " is not a number of metres in (0, 100]");
    if (!out.emplace(id, h).second) throw Error(where + "scene " + std::to_string(id) + " is listed twice");
  }
  if (out.empty()) throw Error(source + ": no scene,height line");
  return out;
}

std::map<int, double> load_gt_heights(const std::string& path) {
  std::vector<std::uint8_t> bytes = read_file_bytes(path, 1ull << 20);
  return parse_gt_heights(std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()), path);
}

void parse_gt_height_args(std::string_view text, std::map<int, double>* table) {
  std::size_t pos = 0;
  while (true) {
    std::size_t comma = text.find(',', pos);
    std::string_view item = trim_field(text.substr(pos, comma == std::string_view::npos ? std::string_view::npos : comma - pos));
    std::size_t eq = item.find('=');
    if (eq == std::string_view::npos) throw Error("--gt-height " + quoted(item) + ": expected SCENE=METRES, e.g. 17=2.85");
    const int id = parse_scene_id(trim_field(item.substr(0, eq)));
    double h = 0;
    if (id < 0) throw Error("--gt-height " + quoted(item) + ": the scene is not a number (17, 017 or images_017)");
    if (!parse_height(trim_field(item.substr(eq + 1)), &h))
      throw Error("--gt-height " + quoted(item) + ": the height is not a number of metres in (0, 100]");
    (*table)[id] = h;
    if (comma == std::string_view::npos) break;
    pos = comma + 1;
  }
}

}  // namespace shle
