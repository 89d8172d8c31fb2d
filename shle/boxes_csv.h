// Boxes from any external detector as CSV, one candidate per line:
//   frame,x0,y0,x1,y1,score
// `frame` is the 0-based position of the image in the sequence's sorted order
// (the `frame` column of the shle output), corners in pixels. An optional header
// line "frame,x0,y0,x1,y1,score", blank lines and lines starting with '#' are
// ignored; fields may be padded with spaces; CRLF line ends are accepted.
#pragma once

#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "shle/types.h"

namespace shle {

struct BoxesFile {
  std::map<int, std::vector<Candidate>> frames;  // candidates per frame, file order
  std::size_t count = 0;
};

// Strict: six fields, a non-negative integer frame, finite numbers, x0 <= x1,
// y0 <= y1. Errors are shle::Error "<source>: line N: <problem>".
BoxesFile parse_boxes_csv(std::string_view text, const std::string& source);
BoxesFile load_boxes_csv(const std::string& path);

}  // namespace shle
