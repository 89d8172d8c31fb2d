// Box sources over the released SHLE stage-1 artefacts (shle/released_boxes.h):
// the per-frame [[x, y], [w, h]] JSON folder and detectron2's COCO results file.
// Both read and check every file when constructed, so a wrong folder or format
// stops the run before any frame is processed, with one line naming the file.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "shle/box_source.h"
#include "shle/calibration.h"
#include "shle/dataset.h"
#include "shle/pipeline.h"

namespace shle {

struct ImageSize {
  int width = 0, height = 0;
};

// The size of every frame's left image from its header (FrameLoader::image_size),
// or the calibration's width x height when the header cannot be read (as
// run_sequence assumes).
std::vector<ImageSize> sequence_image_sizes(const Sequence& sequence, FrameLoader& loader,
                                            const Calibration& calibration);

// The folder the released Stage1/tracking_faster_rcnn.py writes for one scene
// (faster_rcnn_output/tracking_<tracker>_json/images_0XX/): <name>.json for the
// image <name>.png, where <name> is the image file name up to its first '.', as
// the released code names them. It holds the detections and the tracker's boxes,
// so a frame without a file has no box. Errors: no such folder, no .json in it, a
// .json file that names no image of the sequence, two images sharing a <name>, or
// any file that is not a released stage-1 box of its frame's image
// (parse_released_stage1). Files not ending in .json are ignored.
class ReleasedStage1Source : public BoxSource {
 public:
  ReleasedStage1Source(const std::string& dir, const Sequence& sequence, const std::vector<ImageSize>& sizes);
  std::string name() const override { return "released-stage1"; }
  std::vector<Candidate> candidates(const FrameContext& frame) override;
  std::size_t files() const { return files_; }

 private:
  std::vector<std::vector<Candidate>> boxes_;
  std::size_t files_ = 0;
};

// detectron2's coco_instances_results.json (score as the candidate score, file
// order kept; the box rule chooses, e.g. the released widest rule). image_id is
// mapped to a frame:
//   * with `images_json` a file (the COCO dataset file the detector ran on, e.g. the
//     released test2017_images_0XX.json): id -> "file_name" -> the frame whose image
//     has that base name, as the released code looks the id up in that list;
//   * with images_json == "sorted": id k is the k-th image of the sequence in
//     file-name order (ids from 1). An explicit choice: the released dataset file
//     lists the images in os.walk order, which is not sorted, so ids alone cannot
//     be mapped (a file literally named "sorted" is "./sorted").
// Errors: an id that maps to no frame, a box outside its frame's image (beyond
// kReleasedBoxSlack; detectron2 clips to the image, so that means the wrong
// sequence or file), and every parse error.
class CocoResultsSource : public BoxSource {
 public:
  CocoResultsSource(const std::string& results, const std::string& images_json, const Sequence& sequence,
                    const std::vector<ImageSize>& sizes);
  std::string name() const override { return "coco-results"; }
  std::vector<Candidate> candidates(const FrameContext& frame) override;
  std::size_t records() const { return records_; }

 private:
  std::vector<std::vector<Candidate>> boxes_;
  std::size_t records_ = 0;
};

}  // namespace shle
