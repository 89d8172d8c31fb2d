// Data parsers on files written byte by byte, and their malformed variants.
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <functional>
#include <future>
#include <memory>

#include "shle/box_source.h"
#include "shle/boxes_csv.h"
#include "shle/calibration.h"
#include "shle/dataset.h"
#include "shle/disparity_io.h"
#include "shle/error.h"
#include "shle/labelme.h"
#include "tests/error_of.h"
#include "tests/process_memory.h"
#include "shle/height.h"
#include "tests/shle/test_util.h"
#include "weights/json.h"

namespace {

using shletest::TempDir;
using shletest::write_bytes;
using shletest::write_text;

// raw 0, 32, 33, 65535 / 1, 256 as a 2-row, 3-column little-endian uint16 map... 3x2
const std::vector<std::uint8_t> kDat = {0x00, 0x00, 0x20, 0x00, 0x21, 0x00,
                                        0xFF, 0xFF, 0x01, 0x00, 0x00, 0x01};

TEST(Dat, DecodesLittleEndianWithFiveFractionBits) {
  shle::DisparityMap m = shle::parse_dat(kDat.data(), kDat.size(), 3, 2, 5, "t.dat");
  ASSERT_EQ(m.width, 3);
  ASSERT_EQ(m.height, 2);
  EXPECT_EQ(m.at(0, 0), 0.0f);
  EXPECT_EQ(m.at(1, 0), 1.0f);
  EXPECT_EQ(m.at(2, 0), 1.03125f);
  EXPECT_EQ(m.at(0, 1), 2047.96875f);
  EXPECT_EQ(m.at(1, 1), 0.03125f);
  EXPECT_EQ(m.at(2, 1), 8.0f);
  shle::DisparityMap whole = shle::parse_dat(kDat.data(), kDat.size(), 3, 2, 0, "t.dat");
  EXPECT_EQ(whole.at(1, 0), 32.0f);
}

TEST(Dat, WrongSizeIsAnError) {
  EXPECT_THROW_MSG(shle::parse_dat(kDat.data(), kDat.size() - 1, 3, 2, 5, "t.dat"),
                   "t.dat: 11 bytes, expected 12 (3x2 uint16)");
  std::vector<std::uint8_t> longer = kDat;
  longer.push_back(0);
  EXPECT_THROW_MSG(shle::parse_dat(longer.data(), longer.size(), 3, 2, 5, "t.dat"), "13 bytes, expected 12");
  EXPECT_THROW_MSG(shle::parse_dat(kDat.data(), kDat.size(), 0, 2, 5, "t.dat"), "bad disparity size");
  EXPECT_THROW_MSG(shle::parse_dat(kDat.data(), kDat.size(), 3, 2, 16, "t.dat"), "fraction bits");
}

TEST(Dat, ReadsFilesAndReportsProblems) {
  TempDir dir;
  write_bytes(dir / "d.dat", kDat);
  shle::DisparityMap m = shle::read_dat(dir / "d.dat", 3, 2, 5);
  EXPECT_EQ(m.at(2, 1), 8.0f);
  EXPECT_THROW_MSG(shle::read_dat(dir / "d.dat", 1280, 720, 5), "12 bytes, expected 1843200 (1280x720 uint16)");
  EXPECT_THROW_MSG(shle::read_dat(dir / "d.dat", 2, 2, 5), "more than 8 bytes, expected 8");
  EXPECT_THROW_MSG(shle::read_dat(dir / "missing.dat", 3, 2, 5), "missing.dat: cannot open");
  EXPECT_THROW_MSG(shle::read_dat(dir.path(), 3, 2, 5), "is a directory");
  write_bytes(dir / "empty.dat", {});
  EXPECT_THROW_MSG(shle::read_dat(dir / "empty.dat", 3, 2, 5), "0 bytes, expected 12");
}

TEST(Dat, FractionBitsFromName) {
  EXPECT_EQ(shle::dat_fraction_bits("disparity_5_1_2_3_4.dat"), 5);
  EXPECT_EQ(shle::dat_fraction_bits("disparity_4_1_2_3_4.dat"), 4);
  EXPECT_EQ(shle::dat_fraction_bits("disparity_x_1.dat"), 5);
  EXPECT_EQ(shle::dat_fraction_bits("other.dat", 3), 3);
  EXPECT_EQ(shle::dat_fraction_bits("disparity_99_1.dat"), 5);
}

std::vector<std::uint8_t> pfm_bytes(const std::string& header, const std::vector<float>& values, bool little) {
  std::vector<std::uint8_t> b(header.begin(), header.end());
  for (float v : values) {
    std::uint8_t le[4];
    std::memcpy(le, &v, 4);
    if (little)
      b.insert(b.end(), le, le + 4);
    else
      b.insert(b.end(), {le[3], le[2], le[1], le[0]});
  }
  return b;
}

TEST(Pfm, DecodesBottomUpRowsBothEndians) {
  // File rows are bottom to top: the first stored row is the image's last row.
  std::vector<float> stored = {1, 2, 3, 4, 5, 6};  // 3 wide, 2 high
  for (bool little : {true, false}) {
    auto bytes = pfm_bytes(little ? "Pf\n3 2\n-1.0\n" : "Pf\n3 2\n1.0\n", stored, little);
    shle::DisparityMap m = shle::parse_pfm(bytes.data(), bytes.size(), "d.pfm");
    ASSERT_EQ(m.width, 3);
    ASSERT_EQ(m.height, 2);
    EXPECT_EQ(m.at(0, 1), 1.0f);
    EXPECT_EQ(m.at(2, 1), 3.0f);
    EXPECT_EQ(m.at(0, 0), 4.0f);
    EXPECT_EQ(m.at(2, 0), 6.0f);
  }
  auto inf = pfm_bytes("Pf\n1 1\n-1\n", {INFINITY}, true);
  EXPECT_TRUE(std::isinf(shle::parse_pfm(inf.data(), inf.size(), "i.pfm").at(0, 0)));
}

TEST(Pfm, Malformed) {
  std::vector<float> v4 = {1, 2, 3, 4};
  auto p = [&](const std::string& h, std::size_t drop = 0, std::size_t extra = 0) {
    auto b = pfm_bytes(h, v4, true);
    b.resize(b.size() - drop + extra, 0);
    return b;
  };
  auto check = [](const std::vector<std::uint8_t>& b, const char* msg) {
    EXPECT_THROW_MSG(shle::parse_pfm(b.data(), b.size(), "x.pfm"), msg);
  };
  check(p("PF\n2 2\n-1\n"), "colour PFM");
  check(p("P5\n2 2\n-1\n"), "not a PFM file");
  check(p("Pf\n2 2\n-1\n", 1), "PFM data is 15 bytes, expected 16");
  check(p("Pf\n2 2\n-1\n", 0, 4), "PFM data is 20 bytes, expected 16");
  check(p("Pf\n2x 2\n-1\n"), "width '2x' is not a positive integer");
  check(p("Pf\n0 2\n-1\n"), "bad disparity size 0x2");
  check(p("Pf\n9999999 2\n-1\n"), "too large");
  check(p("Pf\n2 2\n0\n"), "scale '0' is not a non-zero number");
  check(p("Pf\n2 2\nnan\n"), "scale 'nan'");
  std::string cut = "Pf\n2";
  check(std::vector<std::uint8_t>(cut.begin(), cut.end()), "truncated PFM header");
  check({}, "not a PFM file");
}

// Found by tests/fuzz/fuzz_disparity: header fields went into the message raw, so a
// control byte in the width (minimized: "Pf\nu\x02 ...") or scale broke the one-line rule.
TEST(Pfm, HeaderFieldsInMessagesAreEscaped) {
  const std::vector<std::string> heads = {std::string("Pf\nu\x02 2\n-1\n"), "Pf\n2 \x1b[31m\n-1\n",
                                          "Pf\n2 2\n-1\x7f\x01\n"};
  for (const std::string& h : heads) {
    std::vector<std::uint8_t> b(h.begin(), h.end());
    b.resize(b.size() + 16, 0);
    std::string m = testutil::error_of([&] { shle::parse_pfm(b.data(), b.size(), "x.pfm"); });
    EXPECT_TRUE(testutil::is_one_printable_line(m)) << m;
    EXPECT_NE(m.find("\\x"), std::string::npos) << m;
  }
}

TEST(Png16, ScaledBySixteenBitScale) {
  std::vector<std::uint16_t> raw = {0, 32, 256, 65535};
  shle::DisparityMap m = shle::disparity_from_u16(raw.data(), 2, 2, 32.0, "d.png");
  EXPECT_EQ(m.at(0, 0), 0.0f);
  EXPECT_EQ(m.at(1, 0), 1.0f);
  EXPECT_EQ(m.at(0, 1), 8.0f);
  EXPECT_EQ(m.at(1, 1), 65535.0f / 32.0f);
  EXPECT_THROW_MSG(shle::disparity_from_u16(raw.data(), 2, 2, 0.0, "d.png"), "disparity scale");
}

TEST(Labelme, ReadsHeightRectanglesNormalised) {
  TempDir dir;
  write_text(dir / "a.json", R"({"version": "5.0.1", "shapes": [
      {"label": "car", "points": [[1, 2], [3, 4]], "shape_type": "rectangle"},
      {"label": "height", "points": [[900.5, 300], [100, 250.25]], "shape_type": "rectangle"},
      {"label": "height", "points": [[10, 20], [30, 20], [20, 40]], "shape_type": "polygon"}],
      "imageWidth": 1280, "imageHeight": 720})");
  shle::LabelmeFile f = shle::load_labelme(dir / "a.json");
  EXPECT_EQ(f.image_width, 1280);
  EXPECT_EQ(f.image_height, 720);
  ASSERT_EQ(f.boxes.size(), 2u);
  EXPECT_EQ(f.boxes[0].x0, 100);
  EXPECT_EQ(f.boxes[0].y0, 250.25);
  EXPECT_EQ(f.boxes[0].x1, 900.5);
  EXPECT_EQ(f.boxes[0].y1, 300);
  EXPECT_EQ(f.boxes[1].x0, 10);
  EXPECT_EQ(f.boxes[1].y1, 40);
}

TEST(Labelme, WriterRoundTrips) {
  std::string text = shle::labelme_json("img.png", 640, 480, {shle::Box{1.5, 2, 300.25, 40}});
  shle::LabelmeFile f = shle::parse_labelme(json::parse(text, "w"), "w");
  ASSERT_EQ(f.boxes.size(), 1u);
  EXPECT_EQ(f.boxes[0].x0, 1.5);
  EXPECT_EQ(f.boxes[0].x1, 300.25);
  EXPECT_EQ(f.image_width, 640);
  EXPECT_TRUE(shle::parse_labelme(json::parse(shle::labelme_json("i.png", 4, 4, {}), "w"), "w").boxes.empty());
}

TEST(Labelme, Malformed) {
  auto bad = [](const std::string& text, const char* msg) {
    EXPECT_THROW_MSG(shle::parse_labelme(json::parse(text, "m.json"), "m.json"), msg);
  };
  bad("[]", "must be a JSON object");
  bad("{}", "no \"shapes\" array");
  bad(R"({"shapes": {}})", "no \"shapes\" array");
  bad(R"({"shapes": [3]})", "shape 0 is not an object");
  bad(R"({"shapes": [{"points": [[1,2],[3,4]]}]})", "shape 0 has no string \"label\"");
  bad(R"({"shapes": [{"label": "height"}]})", "shape 0 has no \"points\" array");
  bad(R"({"shapes": [{"label": "height", "points": [[1,2]]}]})", "fewer than 2 points");
  bad(R"({"shapes": [{"label": "height", "points": [[1,2],[3]]}]})", "not an [x, y] pair");
  bad(R"({"shapes": [{"label": "height", "points": [[1,2],["a",4]]}]})", "not an [x, y] pair");
  bad(R"({"shapes": [], "imageWidth": -3})", "'imageWidth' must be an integer");
  TempDir dir;
  write_text(dir / "broken.json", R"({"shapes": [)");
  EXPECT_THROW_MSG(shle::load_labelme(dir / "broken.json"), "broken.json");
  EXPECT_THROW(shle::load_labelme(dir / "broken.json"), shle::Error);
  EXPECT_THROW_MSG(shle::load_labelme(dir / "none.json"), "none.json");
}

TEST(BoxesCsv, ParsesHeaderCommentsSpacesAndCrlf) {
  shle::BoxesFile f = shle::parse_boxes_csv(
      "frame,x0,y0,x1,y1,score\r\n# a comment\n\n0, 10, 20.5, 30, 40, 0.9\r\n0,1,2,3,4,0.2\n7,5e1,6,70,8,1\n", "b.csv");
  EXPECT_EQ(f.count, 3u);
  ASSERT_EQ(f.frames.at(0).size(), 2u);
  EXPECT_EQ(f.frames.at(0)[0].box.y0, 20.5);
  EXPECT_EQ(f.frames.at(0)[0].score, 0.9);
  EXPECT_EQ(f.frames.at(7)[0].box.x0, 50);
  EXPECT_EQ(f.frames.count(3), 0u);
  EXPECT_EQ(shle::parse_boxes_csv("", "e.csv").count, 0u);
}

TEST(BoxesCsv, Malformed) {
  auto bad = [](const std::string& text, const char* msg) {
    EXPECT_THROW_MSG(shle::parse_boxes_csv(text, "b.csv"), msg);
  };
  bad("0,1,2,3,4\n", "b.csv: line 1: expected 6 fields");
  bad("0,1,2,3,4,5\n0,1,2,3,4,5,6\n", "line 2: expected 6 fields frame,x0,y0,x1,y1,score, got 7");
  bad("-1,1,2,3,4,0.5\n", "frame '-1' is not a frame index");
  bad("a,1,2,3,4,0.5\n", "frame 'a'");
  bad("1,nan,2,3,4,0.5\n", "x0 'nan' is not a finite number");
  bad("1,1,inf,3,4,0.5\n", "y0 'inf'");
  bad("1,1,2,1e999,4,0.5\n", "x1 '1e999'");
  bad("1,1,2,3,4,0x1\n", "score '0x1'");
  bad("1,5,2,3,4,0.5\n", "x1 < x0");
  bad("1,1,2,3,4,\n", "score ''");
  bad("0,1,2,3,4,5\nframe,x0,y0,x1,y1,score\n", "unexpected header");
  bad("frame,a,b,c,d,e\n", "unexpected header");
}

TEST(BoxesCsv, SourceChecksFrameRange) {
  TempDir dir;
  write_text(dir / "b.csv", "0,1,2,3,4,0.5\n5,1,2,3,4,0.5\n");
  EXPECT_THROW_MSG(shle::BoxesFileSource(dir / "b.csv", 5), "frame 5 but the sequence has 5 frames");
  shle::BoxesFileSource src(dir / "b.csv", 6);
  shle::FrameContext ctx;
  ctx.index = 5;
  EXPECT_EQ(src.candidates(ctx).size(), 1u);
  ctx.index = 2;
  EXPECT_TRUE(src.candidates(ctx).empty());
  EXPECT_THROW_MSG(shle::BoxesFileSource(dir / "nope.csv", 6), "nope.csv: cannot open");
}

TEST(Calibration, PlainFormat) {
  shle::Calibration c = shle::parse_calibration(
      json::parse(R"({"fx": 2000, "fy": 1990, "cx": 640.5, "cy": 360, "bf": 240.0, "mount_height": 1.5,
                      "disparity_scale": 256, "width": 640, "height": 480})", "c.json"),
      "c.json");
  EXPECT_EQ(c.intrinsics.fx, 2000);
  EXPECT_EQ(c.intrinsics.fy, 1990);
  EXPECT_EQ(c.intrinsics.cx, 640.5);
  EXPECT_EQ(c.bf, 240);
  EXPECT_EQ(c.mount_height, 1.5);
  EXPECT_EQ(c.disparity_scale, 256);
  EXPECT_EQ(c.width, 640);
  EXPECT_FALSE(c.has_extrinsics);
  c = shle::parse_calibration(json::parse(R"({"fx": 2000, "fy": 2000, "cx": 1, "cy": 2, "baseline": 0.12})", "c"), "c");
  EXPECT_DOUBLE_EQ(c.bf, 240.0);
  EXPECT_EQ(c.mount_height, 1.45);
  EXPECT_EQ(c.disparity_scale, 32);
  EXPECT_EQ(c.width, 1280);
  c = shle::parse_calibration(
      json::parse(R"({"fx": 1, "fy": 1, "cx": 0, "cy": 0, "bf": 1,
                      "rotation": [[1,0,0],[0,1,0],[0,0,1]], "translation": [0, -1.6, 0]})", "c"), "c");
  EXPECT_TRUE(c.has_extrinsics);
  EXPECT_DOUBLE_EQ(c.mount_height, 1.6);
}

TEST(Calibration, PlainMalformed) {
  auto bad = [](const std::string& text, const char* msg) {
    EXPECT_THROW_MSG(shle::parse_calibration(json::parse(text, "c.json"), "c.json"), msg);
  };
  bad("[]", "c.json: calibration must be a JSON object");
  bad(R"({"fy": 1, "cx": 0, "cy": 0, "bf": 1})", "'fx' must be a number");
  bad(R"({"fx": "2", "fy": 1, "cx": 0, "cy": 0, "bf": 1})", "'fx' must be a number");
  bad(R"({"fx": -2, "fy": 1, "cx": 0, "cy": 0, "bf": 1})", "'fx' must be > 0");
  bad(R"({"fx": 2, "fy": 1, "cx": 0, "cy": 0})", "exactly one of 'bf'");
  bad(R"({"fx": 2, "fy": 1, "cx": 0, "cy": 0, "bf": 1, "baseline": 0.1})", "exactly one of 'bf'");
  bad(R"({"fx": 2, "fy": 1, "cx": 0, "cy": 0, "bf": 0})", "'bf' must be > 0");
  bad(R"({"fx": 2, "fy": 1, "cx": 0, "cy": 0, "bf": 1, "fxx": 3})", "unknown key 'fxx'");
  bad(R"({"fx": 2, "fy": 1, "cx": 0, "cy": 0, "bf": 1, "width": 12.5})", "'width' must be an integer");
  bad(R"({"fx": 2, "fy": 1, "cx": 0, "cy": 0, "bf": 1, "rotation": [[1,0,0],[0,1,0],[0,0,1]]})",
      "'rotation' and 'translation' go together");
  bad(R"({"fx": 2, "fy": 1, "cx": 0, "cy": 0, "bf": 1, "rotation": [[2,0,0],[0,1,0],[0,0,1]], "translation": [0,0,0]})",
      "not a rotation matrix");
  bad(R"({"fx": 2, "fy": 1, "cx": 0, "cy": 0, "bf": 1, "rotation": [[1,0],[0,1]], "translation": [0,0,0]})",
      "3x3");
  bad(R"({"fx": 2, "fy": 1, "cx": 0, "cy": 0, "bf": 1, "mount_height": 1.4, "rotation": [[1,0,0],[0,1,0],[0,0,1]], "translation": [0,0,0]})",
      "either 'mount_height' or 'rotation'");
  TempDir dir;
  write_text(dir / "c.json", R"({"fx": 2000,, })");
  EXPECT_THROW_MSG(shle::load_calibration(dir / "c.json"), "c.json: line 1");
  EXPECT_THROW(shle::load_calibration(dir / "c.json"), shle::Error);
  EXPECT_THROW_MSG(shle::load_calibration(dir / "absent.json"), "absent.json");
}

std::string data_array(int n, const std::vector<std::pair<int, double>>& set) {
  std::vector<double> v(n, 0.0);
  for (auto& p : set) v[p.first] = p.second;
  std::string s = "{\"data\": [";
  for (int i = 0; i < n; ++i) s += (i ? ", " : "") + std::to_string(v[i]);
  return s + "]}";
}

TEST(Calibration, SmarterEyeIndices) {
  TempDir dir;
  write_text(dir / "adas_params/calibData.json",
             data_array(50, {{4, 1990.0}, {12, 1985.0}, {39, 650.0}, {41, 652.0}, {40, 355.0}, {42, 357.0}}));
  write_text(dir / "adas_params/depthcalib.json", data_array(8, {{0, 3.5}, {4, 4.75}}));
  shle::Calibration c = shle::load_smartereye_calibration(dir / "adas_params");
  EXPECT_EQ(c.intrinsics.fx, 1990.0);
  EXPECT_EQ(c.intrinsics.fy, 1985.0);
  EXPECT_EQ(c.intrinsics.cy, 356.0);
  EXPECT_EQ(c.intrinsics.cx, 651.0 - 8.0);  // floor(4.75 + 3.5) = 8
  EXPECT_EQ(c.bf, 240.0);
  EXPECT_EQ(c.mount_height, 1.45);
  // The calibData.json path itself works too.
  EXPECT_EQ(shle::load_smartereye_calibration(dir / "adas_params/calibData.json").intrinsics.fx, 1990.0);
}

TEST(Calibration, SmarterEyeMalformed) {
  TempDir dir;
  write_text(dir / "a/calibData.json", data_array(42, {{4, 1}, {12, 1}}));
  write_text(dir / "a/DepthCalib.json", data_array(5, {}));
  EXPECT_THROW_MSG(shle::load_smartereye_calibration(dir / "a"), "\"data\" has 42 entries, need at least 43");
  write_text(dir / "b/calibData.json", data_array(43, {{4, 1}, {12, 1}}));
  EXPECT_THROW_MSG(shle::load_smartereye_calibration(dir / "b"), "no DepthCalib.json");
  write_text(dir / "c/calibData.json", R"({"data": 5})");
  write_text(dir / "c/DepthCalib.json", data_array(5, {}));
  EXPECT_THROW_MSG(shle::load_smartereye_calibration(dir / "c"), "expected an object with a \"data\" array");
  write_text(dir / "d/calibData.json", data_array(43, {}));
  write_text(dir / "d/DepthCalib.json", data_array(5, {}));
  EXPECT_THROW_MSG(shle::load_smartereye_calibration(dir / "d"), "must be > 0");
}

TEST(Dataset, ReleasedLayout) {
  TempDir dir;
  const std::string s = dir / "seq";
  write_bytes(s + "/left_colorimages/L_1_000002_9_9.png", {});
  write_bytes(s + "/left_colorimages/L_1_000001_9_9.png", {});
  write_bytes(s + "/left_colorimages/L_1_000003_9_9.png", {});
  write_bytes(s + "/left_colorimages/short_name.png", {});
  write_bytes(s + "/left_colorimages/L_1_000001_9_9.json", {});
  write_bytes(s + "/disparity_images/disparity_5_1_000001_9_9.dat", {});
  write_bytes(s + "/disparity_images/disparity_4_1_000002_9_9.dat", {});
  shle::Sequence q = shle::scan_sequence(s);
  EXPECT_EQ(q.layout, shle::Layout::DisparityHeight);
  ASSERT_EQ(q.frames.size(), 4u);
  EXPECT_EQ(q.frames[0].image_name, "L_1_000001_9_9.png");
  EXPECT_EQ(q.frames[0].annotation, s + "/left_colorimages/L_1_000001_9_9.json");
  EXPECT_EQ(q.frames[0].disparity, s + "/disparity_images/disparity_5_1_000001_9_9.dat");
  EXPECT_EQ(q.frames[0].format, shle::DisparityFormat::Dat);
  EXPECT_EQ(q.frames[0].fraction_bits, 5);
  EXPECT_EQ(q.frames[1].fraction_bits, 4);
  EXPECT_TRUE(q.frames[2].disparity.empty());
  EXPECT_NE(q.frames[2].problem.find("disparity_5_1_000003_9_9.dat: missing disparity file"), std::string::npos);
  EXPECT_EQ(q.frames[3].image_name, "short_name.png");
  EXPECT_NE(q.frames[3].problem.find("is not <prefix>_<a>_<b>_<c>_<d>.png"), std::string::npos);
  EXPECT_EQ(shle::released_disparity_suffix("left_a_b_c_d"), "_a_b_c_d");
  EXPECT_EQ(shle::released_disparity_suffix("left_a_b_c_d_e"), "_a_b_c_d");
  EXPECT_EQ(shle::released_disparity_suffix("left_a__c_d"), "");
  EXPECT_EQ(shle::released_disparity_suffix("left_a_b_c"), "");
}

TEST(Dataset, PlainLayoutPicksFormatsInOrder) {
  TempDir dir;
  const std::string s = dir / "seq";
  for (const char* stem : {"a", "b", "c", "d"}) write_bytes(s + "/left/" + stem + ".png", {});
  write_bytes(s + "/disparity/a.dat", {});
  write_bytes(s + "/disparity/a.pfm", {});
  write_bytes(s + "/disparity/b.png", {});
  write_bytes(s + "/disparity/c.pfm", {});
  shle::Sequence q = shle::scan_sequence(s);
  EXPECT_EQ(q.layout, shle::Layout::Plain);
  ASSERT_EQ(q.frames.size(), 4u);
  EXPECT_EQ(q.frames[0].format, shle::DisparityFormat::Dat);
  EXPECT_EQ(q.frames[1].format, shle::DisparityFormat::Png16);
  EXPECT_EQ(q.frames[2].format, shle::DisparityFormat::Pfm);
  EXPECT_EQ(q.frames[3].format, shle::DisparityFormat::None);
  EXPECT_NE(q.frames[3].problem.find("missing disparity file"), std::string::npos);
}

TEST(Dataset, BadFolders) {
  TempDir dir;
  EXPECT_THROW_MSG(shle::scan_sequence(dir / "nothing"), "no such sequence folder");
  std::filesystem::create_directories(dir / "x/other");
  EXPECT_THROW_MSG(shle::scan_sequence(dir / "x"), "not a sequence folder");
  std::filesystem::create_directories(dir / "e/left_colorimages");
  EXPECT_THROW_MSG(shle::scan_sequence(dir / "e"), "no .png images (empty sequence)");
  std::filesystem::create_directories(dir / "p/left");
  write_bytes(dir / "p/left/readme.txt", {});
  EXPECT_THROW_MSG(shle::scan_sequence(dir / "p"), "empty sequence");
}

}  // namespace

// Issue 12, finding 5: input bytes quoted in errors are escaped and cut.
TEST(HostileMessages, CalibrationKeyAndBoxesFieldsStayOnePrintableLine) {
  const std::string h = testutil::hostile_text();
  // A JSON key with escaped control characters decodes to the raw bytes.
  const std::string calib = "{\"fx\": 2, \"fy\": 1, \"cx\": 0, \"cy\": 0, \"bf\": 1, \"a"
                            "\\n\\r\\u001b[31m\\u007f" + std::string(5000, 'z') + "\": 3}";
  const std::string m1 =
      testutil::error_of([&] { shle::parse_calibration(json::parse(calib, "c.json"), "c.json"); });
  EXPECT_NE(m1.find("unknown key 'a\\x0a\\x0d\\x1b[31m\\x7fzz"), std::string::npos) << m1;
  EXPECT_TRUE(testutil::is_one_printable_line(m1, 400)) << m1.size();
  for (const std::string& row : {h + ",1,2,3,4,0.5\n", "1," + h + ",2,3,4,0.5\n", "1,1,2,3,4," + h + "\n"}) {
    const std::string m = testutil::error_of([&] { shle::parse_boxes_csv(row, "b.csv"); });
    EXPECT_TRUE(testutil::is_one_printable_line(m, 400)) << m.size() << ": " << m.substr(0, 200);
  }
}

// Issue 12, rows 8-10: limits before allocation, special files, non-finite values.
namespace {

// Runs `f` on another thread and fails (instead of hanging) if it blocks.
std::string error_within_seconds(const std::function<void()>& f, int seconds) {
  auto result = std::async(std::launch::async, [&] { return testutil::error_of(f); });
  if (result.wait_for(std::chrono::seconds(seconds)) != std::future_status::ready) {
    ADD_FAILURE() << "blocked for more than " << seconds << " s";
    std::_Exit(1);  // the blocked thread cannot be joined
  }
  return result.get();
}

}  // namespace

TEST(HostileFiles, FifoCalibrationAndBoxesAreRefusedWithoutBlocking) {
  TempDir dir;
  const std::string calib = dir / "calib.json", boxes = dir / "boxes.csv", dat = dir / "d.dat";
  for (const std::string& p : {calib, boxes, dat}) ASSERT_EQ(::mkfifo(p.c_str(), 0600), 0);
  EXPECT_EQ(error_within_seconds([&] { shle::load_calibration(calib); }, 10),
            calib + ": is a pipe (FIFO), expected a regular file");
  EXPECT_EQ(error_within_seconds([&] { shle::load_boxes_csv(boxes); }, 10),
            boxes + ": is a pipe (FIFO), expected a regular file");
  EXPECT_EQ(error_within_seconds([&] { shle::read_dat(dat, 3, 2, 5); }, 10),
            dat + ": is a pipe (FIFO), expected a regular file");
  EXPECT_EQ(error_within_seconds([&] { shle::read_pfm("/dev/zero"); }, 10),
            "/dev/zero: is a device, expected a regular file");
}

TEST(HostileFiles, CalibratedSizeIsLimitedAndCommitsNoMemory) {
  const std::string base = "{\"fx\": 700, \"fy\": 700, \"cx\": 640, \"cy\": 360, \"bf\": 240";
  // 65535 x 65535 used to end in "shle: std::bad_alloc" with no file named.
  EXPECT_EQ(testutil::error_of([&] {
              shle::parse_calibration(json::parse(base + ", \"width\": 65535, \"height\": 65535}", "c.json"), "c.json");
            }),
            "c.json: 'width' x 'height' is 65535x65535, above the limit of 256 Mpx");
  // 12000 x 12000 is allowed, and building the estimator no longer preallocates
  // 3.4 GB of scratch for it (only the capped 4 Mpx).
  shle::Calibration c =
      shle::parse_calibration(json::parse(base + ", \"width\": 12000, \"height\": 12000}", "c.json"), "c.json");
  const long before = testutil::rss_kib();
  auto est = std::make_unique<shle::HeightEstimator>(c, shle::HeightOptions{});
  const long grown_mib = (testutil::rss_kib() - before) / 1024;
  EXPECT_LT(grown_mib, 400) << "the estimator committed " << grown_mib << " MiB";
}

TEST(HostileFiles, BaselineTimesFocalLengthOverflowIsAnError) {
  EXPECT_EQ(testutil::error_of([&] {
              shle::parse_calibration(
                  json::parse("{\"fx\": 1e300, \"fy\": 1, \"cx\": 0, \"cy\": 0, \"baseline\": 1e300}", "c.json"),
                  "c.json");
            }),
            "c.json: 'baseline' x 'fx' overflows to infinity (inf)");
}

TEST(HostileFiles, GridStepIsBoundedBeforeAnyLoop) {
  shle::HeightOptions o;
  o.grid_step = 1e-9;  // used to loop over up to 2^52 KDE grid points
  EXPECT_EQ(testutil::error_of([&] { shle::validate(o); }),
            "KDE grid step must be a number in [0.001, 1000] metres (kMinGridStep, kMaxGridStep)");
  o.grid_step = std::nan("");
  EXPECT_THROW(shle::validate(o), shle::Error);
}

TEST(HostileFiles, AllNanPfmSaysWhyThereIsNoHeight) {
  // A 4x4 little-endian PFM of NaN: the height stage names the NaNs.
  std::string pfm = "Pf\n4 4\n-1\n";
  const float nan = std::nanf("");
  for (int i = 0; i < 16; ++i) pfm.append(reinterpret_cast<const char*>(&nan), 4);
  shle::DisparityMap m =
      shle::parse_pfm(reinterpret_cast<const std::uint8_t*>(pfm.data()), pfm.size(), "nan.pfm");
  shle::Calibration c;
  c.width = 4;
  c.height = 4;
  shle::HeightEstimator est(c, shle::HeightOptions{});
  shle::Box box{0, 0, 4, 4};
  shle::HeightResult r = est.estimate(m, box);
  EXPECT_FALSE(r.has_height);
  EXPECT_NE(r.problem.find("no valid disparity in the box (16 of its 16 values are NaN or Inf)"), std::string::npos)
      << r.problem;
}
