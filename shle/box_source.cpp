#include "shle/box_source.h"

#include <filesystem>

#include "shle/error.h"
#include "shle/labelme.h"

namespace shle {

std::vector<Candidate> AnnotationBoxSource::candidates(const FrameContext& frame) {
  std::vector<Candidate> out;
  std::error_code ec;
  if (!frame.files || !std::filesystem::exists(frame.files->annotation, ec)) return out;
  LabelmeFile f = load_labelme(frame.files->annotation);
  for (const Box& b : f.boxes) out.push_back(Candidate{b, 1.0});
  return out;
}

BoxesFileSource::BoxesFileSource(const std::string& path, std::size_t frame_count)
    : file_(load_boxes_csv(path)) {
  if (!file_.frames.empty() && static_cast<std::size_t>(file_.frames.rbegin()->first) >= frame_count)
    throw Error(path + ": frame " + std::to_string(file_.frames.rbegin()->first) + " but the sequence has " +
                std::to_string(frame_count) + " frames (frames count from 0)");
}

std::vector<Candidate> BoxesFileSource::candidates(const FrameContext& frame) {
  auto it = file_.frames.find(frame.index);
  return it == file_.frames.end() ? std::vector<Candidate>{} : it->second;
}

}  // namespace shle
