// image_io against Pillow: the PNG/JPEG files and Pillow's pixels (converted to each
// channel count as stb_image did) come from tests/reference/image_io_ref.py (ctest
// fixture ref_image_io_ref); our PNGs are read back by Pillow.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "apps/common/image_io.h"
#include "apps/common/output_files.h"

namespace fs = std::filesystem;
using Bytes = std::vector<std::uint8_t>;

namespace {

const std::string kDir = std::string(ROADNN_REF_DIR) + "/image_io";

Bytes read_raw(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return Bytes(std::istreambuf_iterator<char>(f), {});
}

struct Case {
  std::string file, raw;
  int want = 0, keep16 = 0, width = 0, height = 0, channels = 0, depth = 0, tol = 0;
};

std::vector<Case> manifest() {
  std::ifstream f(kDir + "/manifest.txt");
  std::vector<Case> cases;
  std::string line;
  while (std::getline(f, line)) {
    std::istringstream s(line);
    Case c;
    if (s >> c.file >> c.want >> c.keep16 >> c.width >> c.height >> c.channels >> c.depth >> c.raw >> c.tol)
      cases.push_back(c);
  }
  return cases;
}

void compare(const std::vector<Case>& cases, const std::string& ext) {
  int n = 0;
  for (const Case& c : cases) {
    if (c.file.size() < ext.size() || c.file.compare(c.file.size() - ext.size(), ext.size(), ext) != 0) continue;
    ++n;
    SCOPED_TRACE(c.file + " want " + std::to_string(c.want) + " keep16 " + std::to_string(c.keep16));
    imageio::Image img = imageio::load(kDir + "/" + c.file, c.want, c.keep16 != 0);
    ASSERT_EQ(img.width, c.width);
    ASSERT_EQ(img.height, c.height);
    ASSERT_EQ(img.channels, c.channels);
    ASSERT_EQ(img.bit_depth, c.depth);
    Bytes want = read_raw(kDir + "/" + c.raw);
    Bytes got;
    if (img.bit_depth == 16) {
      for (std::uint16_t v : img.u16) {
        got.push_back(static_cast<std::uint8_t>(v & 0xFF));
        got.push_back(static_cast<std::uint8_t>(v >> 8));
      }
      EXPECT_TRUE(img.u8.empty());
    } else {
      got = img.u8;
      EXPECT_TRUE(img.u16.empty());
    }
    ASSERT_EQ(got.size(), want.size());
    int worst = 0;
    std::size_t differ = 0;
    for (std::size_t i = 0; i < got.size(); ++i) {
      int d = std::abs(int(got[i]) - int(want[i]));
      worst = std::max(worst, d);
      differ += d != 0;
    }
    EXPECT_LE(worst, c.tol) << differ << " of " << got.size() << " bytes differ";
    // The header probe agrees with the file.
    imageio::ImageInfo info = imageio::probe(kDir + "/" + c.file);
    EXPECT_EQ(info.width, c.width);
    EXPECT_EQ(info.height, c.height);
    if (c.want == 0) {
      EXPECT_EQ(info.channels, c.channels);
    }
  }
  EXPECT_GT(n, 0) << "no " << ext << " cases in " << kDir << "/manifest.txt";
}

}  // namespace

TEST(ImageIoReference, PngPixelsMatchPillow) { compare(manifest(), ".png"); }

TEST(ImageIoReference, JpegPixelsMatchPillowExactly) { compare(manifest(), ".jpg"); }

TEST(ImageIoReference, PillowReadsOurPngsExactly) {
  std::string dir = std::string(ROADNN_BINARY_DIR) + "/test_tmp/apps/ImageIoReference.encode";
  fs::remove_all(dir);
  fs::create_directories(dir);
  struct Shape {
    int w, h, c;
  };
  for (Shape s : {Shape{37, 23, 1}, Shape{37, 23, 2}, Shape{37, 23, 3}, Shape{37, 23, 4}, Shape{1, 1, 3},
                  Shape{640, 360, 3}}) {
    Bytes px(std::size_t(s.w) * s.h * s.c);
    for (std::size_t i = 0; i < px.size(); ++i) px[i] = static_cast<std::uint8_t>((i * 131 + i / 5 + (i >> 9)) & 0xFF);
    std::string stem = dir + "/enc_" + std::to_string(s.w) + "x" + std::to_string(s.h) + "x" + std::to_string(s.c);
    imageio::save_png(stem + ".png", px.data(), s.w, s.h, s.c);
    outputs::write_file(stem + ".raw", px.data(), px.size());
    EXPECT_EQ(imageio::load(stem + ".png").u8, px);  // and our own decoder, too
  }
  std::string cmd = std::string(ROADNN_PYTHON) + " " + ROADNN_SOURCE_DIR + "/tests/reference/image_io_ref.py --verify " + dir;
  EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
}
