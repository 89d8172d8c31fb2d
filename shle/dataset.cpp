#include "shle/dataset.h"

#include <algorithm>
#include <filesystem>
#include <map>

#include "shle/disparity_io.h"
#include "shle/error.h"

namespace shle {
namespace {

namespace fs = std::filesystem;

bool is_dir(const fs::path& p) {
  std::error_code ec;
  return fs::is_directory(p, ec);
}

bool is_file(const fs::path& p) {
  std::error_code ec;
  return fs::exists(p, ec) && !fs::is_directory(p, ec);
}

std::vector<std::string> list_files(const fs::path& dir, const std::string& ext) {
  std::vector<std::string> names;
  std::error_code ec;
  fs::directory_iterator it(dir, ec), end;
  if (ec) throw Error(dir.string() + ": cannot list (" + ec.message() + ")");
  for (; it != end; it.increment(ec)) {
    if (ec) throw Error(dir.string() + ": cannot list (" + ec.message() + ")");
    std::string name = it->path().filename().string();
    std::error_code e2;
    if (it->is_directory(e2)) continue;
    if (name.size() > ext.size() && name.compare(name.size() - ext.size(), ext.size(), ext) == 0)
      names.push_back(name);
  }
  std::sort(names.begin(), names.end());
  return names;
}

std::string stem_of(const std::string& name) { return name.substr(0, name.rfind('.')); }

}  // namespace

const char* layout_name(Layout layout) {
  return layout == Layout::DisparityHeight ? "disparity-height" : "plain";
}

std::string released_disparity_suffix(const std::string& stem) {
  // The released code splits the name at '_' and joins fields 2..5.
  std::vector<std::string> fields;
  std::size_t start = 0;
  while (true) {
    std::size_t us = stem.find('_', start);
    fields.push_back(stem.substr(start, us == std::string::npos ? std::string::npos : us - start));
    if (us == std::string::npos) break;
    start = us + 1;
  }
  if (fields.size() < 5) return "";
  std::string out;
  for (int i = 1; i <= 4; ++i) {
    if (fields[i].empty()) return "";
    out += "_" + fields[i];
  }
  return out;
}

Sequence scan_sequence(const std::string& dir) {
  fs::path root(dir);
  if (!is_dir(root)) throw Error(dir + ": no such sequence folder");
  Sequence seq;
  seq.dir = dir;
  if (is_dir(root / "left_colorimages")) {
    seq.layout = Layout::DisparityHeight;
    fs::path images = root / "left_colorimages", disp = root / "disparity_images";
    std::map<std::string, std::string> by_suffix;  // "_a_b_c_d" -> file name
    if (is_dir(disp)) {
      for (const std::string& name : list_files(disp, ".dat")) {
        if (name.compare(0, 10, "disparity_") != 0) continue;
        std::string s = stem_of(name);
        std::size_t bits_end = s.find('_', 10);
        if (bits_end == std::string::npos) continue;
        by_suffix.emplace(s.substr(bits_end), name);
      }
    }
    for (const std::string& name : list_files(images, ".png")) {
      FrameFiles f;
      f.image_name = name;
      f.stem = stem_of(name);
      f.image = (images / name).string();
      f.annotation = (images / (f.stem + ".json")).string();
      std::string suffix = released_disparity_suffix(f.stem);
      if (suffix.empty()) {
        f.problem = name + ": name is not <prefix>_<a>_<b>_<c>_<d>.png, cannot find its disparity";
      } else if (!is_dir(disp)) {
        f.problem = (root / "disparity_images").string() + ": no such folder";
      } else {
        auto it = by_suffix.find(suffix);
        if (it == by_suffix.end()) {
          f.problem = (disp / ("disparity_5" + suffix + ".dat")).string() + ": missing disparity file";
        } else {
          f.disparity = (disp / it->second).string();
          f.format = DisparityFormat::Dat;
          f.fraction_bits = dat_fraction_bits(it->second);
        }
      }
      seq.frames.push_back(std::move(f));
    }
    if (seq.frames.empty()) throw Error(images.string() + ": no .png images (empty sequence)");
    return seq;
  }
  if (is_dir(root / "left")) {
    seq.layout = Layout::Plain;
    fs::path images = root / "left", disp = root / "disparity";
    for (const std::string& name : list_files(images, ".png")) {
      FrameFiles f;
      f.image_name = name;
      f.stem = stem_of(name);
      f.image = (images / name).string();
      f.annotation = (images / (f.stem + ".json")).string();
      static const std::pair<const char*, DisparityFormat> kinds[] = {
          {".dat", DisparityFormat::Dat}, {".png", DisparityFormat::Png16}, {".pfm", DisparityFormat::Pfm}};
      for (const auto& k : kinds) {
        fs::path p = disp / (f.stem + k.first);
        if (is_file(p)) {
          f.disparity = p.string();
          f.format = k.second;
          break;
        }
      }
      if (f.disparity.empty())
        f.problem = (disp / f.stem).string() + ".dat|.png|.pfm: missing disparity file";
      seq.frames.push_back(std::move(f));
    }
    if (seq.frames.empty()) throw Error(images.string() + ": no .png images (empty sequence)");
    return seq;
  }
  throw Error(dir + ": not a sequence folder (expected left_colorimages/ or left/ inside)");
}

}  // namespace shle
