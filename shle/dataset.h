// Sequence folders. Two layouts are recognised:
//   released "Disparity Height": SCENE/left_colorimages/<prefix>_<a>_<b>_<c>_<d>.png
//       with LabelMe <same stem>.json beside each image, and
//       SCENE/disparity_images/disparity_<bits>_<a>_<b>_<c>_<d>.dat
//       (1280x720 little-endian uint16 with <bits> = 5 fractional bits);
//   plain: SCENE/left/<stem>.png (LabelMe <stem>.json beside it) and
//       SCENE/disparity/<stem>.dat | <stem>.png (16-bit, / disparity_scale) |
//       <stem>.pfm, looked up in that order.
// Frames are the images sorted by file name (byte order), as the released code
// sorts them.
#pragma once

#include <string>
#include <vector>

namespace shle {

enum class Layout { DisparityHeight, Plain };
enum class DisparityFormat { None, Dat, Png16, Pfm };

const char* layout_name(Layout layout);

struct FrameFiles {
  std::string image_name;  // file name of the left image
  std::string stem;        // ... without extension
  std::string image;       // path of the left image
  std::string annotation;  // path where its LabelMe file would be (may not exist)
  std::string disparity;   // path of the disparity file, "" when none was found
  DisparityFormat format = DisparityFormat::None;
  int fraction_bits = 5;   // .dat only
  std::string problem;     // why there is no disparity file
};

struct Sequence {
  std::string dir;
  Layout layout = Layout::Plain;
  std::vector<FrameFiles> frames;
};

// Throws shle::Error when `dir` is missing, has neither layout, or holds no image.
Sequence scan_sequence(const std::string& dir);

// "<prefix>_<a>_<b>_<c>_<d>" -> "_<a>_<b>_<c>_<d>" (the part the disparity file
// name shares with the image), or "" when the stem has fewer than five fields.
std::string released_disparity_suffix(const std::string& stem);

}  // namespace shle
