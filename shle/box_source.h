// Where the candidate boxes of a frame come from. The pipeline asks a BoxSource
// for the candidates of each frame in order, then a box rule (box_rules.h) picks
// one. A detector is one more implementation that sets needs_image() and reads
// the pixels from the context.
#pragma once

#include <string>
#include <vector>

#include "shle/boxes_csv.h"
#include "shle/dataset.h"
#include "shle/types.h"

namespace shle {

struct FrameContext {
  int index = 0;                     // position in the sequence
  const FrameFiles* files = nullptr;
  const RgbImage* image = nullptr;   // decoded left image when needs_image(), else null
};

class BoxSource {
 public:
  virtual ~BoxSource() = default;
  // Name written to the box_source column: "annotations", "boxes-file", ...
  virtual std::string name() const = 0;
  virtual bool needs_image() const { return false; }
  // Candidates for the frame (possibly none). Throws shle::Error for a bad input
  // of this frame only (e.g. a malformed annotation); the pipeline reports it and
  // treats the frame as having no candidate.
  virtual std::vector<Candidate> candidates(const FrameContext& frame) = 0;
};

// LabelMe rectangles labelled "height" next to each image, score 1. A frame
// without an annotation file has no candidate. A file with the released stage-1
// writer's exact layout (its points are [x, y], [w, h]) is refused for its frame
// rather than read as corners (load_labelme).
class AnnotationBoxSource : public BoxSource {
 public:
  std::string name() const override { return "annotations"; }
  std::vector<Candidate> candidates(const FrameContext& frame) override;
};

// A frame,x0,y0,x1,y1,score CSV (boxes_csv.h). Frames beyond the sequence are
// an error at construction.
class BoxesFileSource : public BoxSource {
 public:
  BoxesFileSource(const std::string& path, std::size_t frame_count);
  std::string name() const override { return "boxes-file"; }
  std::vector<Candidate> candidates(const FrameContext& frame) override;

 private:
  BoxesFile file_;
};

}  // namespace shle
