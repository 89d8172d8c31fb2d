#include "shle/released_box_source.h"

#include <algorithm>
#include <filesystem>
#include <map>

#include "shle/error.h"
#include "shle/released_boxes.h"
#include "weights/quote_name.h"

namespace shle {
namespace {

namespace fs = std::filesystem;

std::string first_dot_stem(const std::string& name) { return name.substr(0, name.find('.')); }

void check_sizes(const Sequence& seq, const std::vector<ImageSize>& sizes) {
  if (sizes.size() != seq.frames.size())
    throw Error("image sizes for " + std::to_string(sizes.size()) + " frames but the sequence has " +
                std::to_string(seq.frames.size()));
}

}  // namespace

std::vector<ImageSize> sequence_image_sizes(const Sequence& seq, FrameLoader& loader, const Calibration& cal) {
  std::vector<ImageSize> out(seq.frames.size());
  for (std::size_t i = 0; i < seq.frames.size(); ++i)
    if (!loader.image_size(seq.frames[i].image, &out[i].width, &out[i].height)) out[i] = {cal.width, cal.height};
  return out;
}

ReleasedStage1Source::ReleasedStage1Source(const std::string& dir, const Sequence& seq,
                                           const std::vector<ImageSize>& sizes) {
  check_sizes(seq, sizes);
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw Error(dir + ": no such folder (released stage-1 boxes)");
  std::map<std::string, std::size_t> frame_of;  // <name> -> frame
  for (std::size_t i = 0; i < seq.frames.size(); ++i) {
    const std::string key = first_dot_stem(seq.frames[i].image_name);
    auto ins = frame_of.emplace(key, i);
    if (!ins.second)
      throw Error(seq.frames[i].image + ": shares the stage-1 name " + key + ".json with " +
                  seq.frames[ins.first->second].image_name + " (the released code names files up to the first '.')");
  }
  std::vector<std::string> names;
  fs::directory_iterator it(dir, ec), end;
  if (ec) throw Error(dir + ": cannot list (" + ec.message() + ")");
  for (; it != end; it.increment(ec)) {
    if (ec) throw Error(dir + ": cannot list (" + ec.message() + ")");
    const std::string name = it->path().filename().string();
    if (name.size() > 5 && name.compare(name.size() - 5, 5, ".json") == 0) names.push_back(name);
  }
  std::sort(names.begin(), names.end());
  if (names.empty()) throw Error(dir + ": no .json files (released stage-1 boxes)");
  boxes_.resize(seq.frames.size());
  for (const std::string& name : names) {
    const std::string path = (fs::path(dir) / name).string();
    auto f = frame_of.find(name.substr(0, name.size() - 5));
    if (f == frame_of.end() || first_dot_stem(name) != f->first)
      throw Error(path + ": no image of that name in " + seq.dir + " (wrong scene folder?)");
    const ImageSize& sz = sizes[f->second];
    boxes_[f->second].push_back(Candidate{load_released_stage1(path, sz.width, sz.height), 1.0});
    ++files_;
  }
}

std::vector<Candidate> ReleasedStage1Source::candidates(const FrameContext& frame) {
  if (frame.index < 0 || static_cast<std::size_t>(frame.index) >= boxes_.size()) return {};
  return boxes_[frame.index];
}

CocoResultsSource::CocoResultsSource(const std::string& results, const std::string& images_json,
                                     const Sequence& seq, const std::vector<ImageSize>& sizes) {
  check_sizes(seq, sizes);
  std::vector<CocoDetection> dets = load_coco_results(results);
  if (images_json.empty())
    throw Error(results + ": COCO image ids need the dataset file that lists the images (or \"sorted\")");
  const bool sorted = images_json == "sorted";
  std::map<std::int64_t, std::size_t> frame_of_id;
  if (!sorted) {
    std::map<std::string, std::size_t> frame_of_name;
    for (std::size_t i = 0; i < seq.frames.size(); ++i) frame_of_name.emplace(seq.frames[i].image_name, i);
    for (const auto& [id, name] : load_coco_images(images_json)) {
      auto f = frame_of_name.find(name);
      if (f == frame_of_name.end())
        throw Error(images_json + ": image " + weights::quote_name(name) + " (id " + std::to_string(id) +
                    ") is not in " + seq.dir);
      frame_of_id.emplace(id, f->second);
    }
  }
  boxes_.resize(seq.frames.size());
  std::size_t index = 0;
  for (const CocoDetection& d : dets) {
    const std::string where = results + ": record " + std::to_string(index++);
    std::size_t frame = 0;
    if (!sorted) {
      auto f = frame_of_id.find(d.image_id);
      if (f == frame_of_id.end())
        throw Error(where + ": image_id " + std::to_string(d.image_id) + " is not in " + images_json);
      frame = f->second;
    } else {
      if (d.image_id > static_cast<std::int64_t>(seq.frames.size()))
        throw Error(where + ": image_id " + std::to_string(d.image_id) + " but the sequence has " +
                    std::to_string(seq.frames.size()) + " images (ids count from 1 in file-name order)");
      frame = static_cast<std::size_t>(d.image_id - 1);
    }
    const ImageSize& sz = sizes[frame];
    const Box b = d.box();
    if (b.x0 < -kReleasedBoxSlack || b.y0 < -kReleasedBoxSlack || b.x1 > sz.width + kReleasedBoxSlack ||
        b.y1 > sz.height + kReleasedBoxSlack)
      throw Error(where + ": bbox reaches outside the " + std::to_string(sz.width) + "x" +
                  std::to_string(sz.height) + " image " + seq.frames[frame].image_name);
    boxes_[frame].push_back(Candidate{b, d.score});
    ++records_;
  }
}

std::vector<Candidate> CocoResultsSource::candidates(const FrameContext& frame) {
  if (frame.index < 0 || static_cast<std::size_t>(frame.index) >= boxes_.size()) return {};
  return boxes_[frame.index];
}

}  // namespace shle
