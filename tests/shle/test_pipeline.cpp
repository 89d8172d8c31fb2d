// Whole sequences through run_sequence: box sources, gap filling, the Kalman
// stage, and every bad input the pipeline must survive frame by frame.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "apps/shle/frame_loader.h"
#include "apps/shle/synth_writer.h"
#include "shle/pipeline.h"
#include "tests/process_memory.h"
#include "tests/shle/test_util.h"

namespace {

namespace fs = std::filesystem;
using shletest::TempDir;

shle::synth::SceneSpec small_scene(std::uint64_t seed) {
  shle::synth::SceneSpec s;
  s.seed = seed;
  s.frames = 8;
  s.start_distance = 40;
  s.end_distance = 25;
  s.width = 640;
  s.height = 360;
  s.fx = s.fy = 1000;
  s.cx = 320;
  s.cy = 180;
  s.miss_rate = 0;
  return s;
}

struct Fixture {
  TempDir dir;
  std::string seq;
  shle::Calibration cal;
  std::vector<shle::synth::Frame> truth;
  explicit Fixture(shleapp::SynthLayout layout = shleapp::SynthLayout::Released) {
    shle::synth::Scene scene(small_scene(31));
    seq = dir / "seq";
    shleapp::write_synth_scene(scene, seq, layout);
    cal = shle::load_calibration(seq + "/calib.json");
    for (int k = 0; k < scene.frame_count(); ++k) truth.push_back(scene.render(k));
  }
  shle::SequenceRun run(const shle::PipelineOptions& opt = {}) {
    shle::Sequence s = shle::scan_sequence(seq);
    shle::AnnotationBoxSource src;
    shleapp::PngFrameLoader loader;
    return shle::run_sequence(s, cal, src, loader, opt);
  }
};

bool has_problem(const shle::FrameRecord& r, const std::string& text) {
  for (const std::string& p : r.problems)
    if (p.find(text) != std::string::npos) return true;
  return false;
}

TEST(Pipeline, AnnotationsKalmanAndSceneHeight) {
  Fixture f;
  shle::PipelineOptions opt;
  opt.has_gt_height = true;
  opt.gt_height = 3.3;
  shle::SequenceRun run = f.run(opt);
  ASSERT_EQ(run.frames.size(), 8u);
  EXPECT_EQ(run.frames_with_box, 8u);
  EXPECT_EQ(run.frames_tracked, 0u);
  EXPECT_EQ(run.frames_used, 8u);
  std::vector<double> raw;
  for (const shle::FrameRecord& r : run.frames) {
    EXPECT_EQ(r.box_source, "annotations");
    ASSERT_TRUE(r.stage2.has_height) << r.stage2.problem;
    EXPECT_NEAR(r.stage2.height, 3.3, 0.3);
    EXPECT_TRUE(r.problems.empty());
    raw.push_back(r.stage2.height);
  }
  std::vector<double> kal = geometry::kalman_smooth(raw, {});
  double mean = 0;
  for (std::size_t i = 0; i < kal.size(); ++i) {
    EXPECT_EQ(run.frames[i].filtered, kal[i]);
    mean += kal[i] / kal.size();
  }
  EXPECT_NEAR(run.heights.scene_height, mean, 1e-12);
  ASSERT_TRUE(run.has_errors);
  EXPECT_NEAR(run.scene_error.he, run.heights.scene_height - 3.3, 1e-12);
  EXPECT_EQ(run.box_metric_frames, 8u);
  EXPECT_EQ(run.box_metrics.cpd, 0.0);  // the chosen boxes are the annotations

  opt.temporal.kalman_compat = true;
  shle::SequenceRun compat = f.run(opt);
  std::vector<double> rel = geometry::kalman_smooth_released(raw, {});
  for (std::size_t i = 0; i < rel.size(); ++i) EXPECT_EQ(compat.frames[i].filtered, rel[i]);
  EXPECT_EQ(compat.frames.back().filtered, 0.0);

  opt.temporal.kalman_compat = false;
  opt.temporal.use_kalman = false;
  shle::SequenceRun plain = f.run(opt);
  for (std::size_t i = 0; i < raw.size(); ++i) EXPECT_EQ(plain.frames[i].filtered, raw[i]);
}

TEST(Pipeline, TrackerFillsGapsBetweenBoxesOnly) {
  Fixture f;
  auto json = [&](int k) {
    shle::Sequence s = shle::scan_sequence(f.seq);
    return s.frames[k].annotation;
  };
  for (int k : {0, 3, 4}) fs::remove(json(k));
  shle::SequenceRun run = f.run();
  EXPECT_FALSE(run.frames[0].has_box);  // before the first box: never tracked
  EXPECT_EQ(run.frames[0].box_source, "");
  EXPECT_FALSE(run.frames[0].stage2.has_height);
  for (int k : {3, 4}) {
    const shle::FrameRecord& r = run.frames[k];
    ASSERT_TRUE(r.has_box) << k;
    EXPECT_EQ(r.box_source, "tracker");
    EXPECT_EQ(r.box.width(), std::trunc(run.frames[2].box.width()));  // fixed size
    shle::CentreDistance c;
    ASSERT_TRUE(shle::centre_distance(r.box, f.truth[k].box, &c));
    EXPECT_LT(c.cpd, 8.0) << k;
    EXPECT_TRUE(r.stage2.has_height);
  }
  EXPECT_EQ(run.frames_tracked, 2u);
  EXPECT_EQ(run.frames_used, 7u);
  // After the last box: never tracked.
  fs::remove(json(7));
  run = f.run();
  EXPECT_FALSE(run.frames[7].has_box);
  // No tracker: gaps stay empty.
  shle::PipelineOptions none;
  none.tracker = "none";
  run = f.run(none);
  EXPECT_FALSE(run.frames[3].has_box);
  EXPECT_EQ(run.frames_tracked, 0u);
}

TEST(Pipeline, BadFramesAreReportedAndSkipped) {
  Fixture f;
  shle::Sequence s = shle::scan_sequence(f.seq);
  // Frame 1: .dat one row short. Frame 2: no .dat. Frame 5: all zero.
  // Frame 6: malformed annotation (tracked from 5 to 7 instead).
  {
    std::vector<std::uint8_t> short_dat(2 * 640 * 359, 0x40);
    shletest::write_bytes(s.frames[1].disparity, short_dat);
  }
  fs::remove(s.frames[2].disparity);
  shletest::write_bytes(s.frames[5].disparity, std::vector<std::uint8_t>(2 * 640 * 360, 0));
  shletest::write_text(s.frames[6].annotation, "{\"shapes\": [ {\"label\": \"height\", \"points\": [[1, 2]]} ]}");
  shle::PipelineOptions opt;
  opt.has_gt_height = true;
  opt.gt_height = 3.3;
  shle::SequenceRun run = f.run(opt);
  EXPECT_TRUE(has_problem(run.frames[1], "bytes, expected 460800 (640x360 uint16)"));
  EXPECT_FALSE(run.frames[1].stage2.has_height);
  EXPECT_TRUE(has_problem(run.frames[2], "missing disparity file"));
  EXPECT_FALSE(run.frames[2].stage2.has_height);
  EXPECT_TRUE(has_problem(run.frames[5], "no valid disparity in the box"));
  EXPECT_FALSE(run.frames[5].stage2.has_height);
  EXPECT_TRUE(has_problem(run.frames[6], "fewer than 2 points"));
  EXPECT_EQ(run.frames[6].box_source, "tracker");
  EXPECT_EQ(run.frames_used, 5u);
  for (const shle::FrameRecord& r : run.frames) {
    EXPECT_EQ(r.has_filtered, r.stage2.has_height);
    if (r.has_filtered) {
      EXPECT_TRUE(std::isfinite(r.filtered));
    }
  }
  EXPECT_TRUE(std::isfinite(run.heights.scene_height));
}

TEST(Pipeline, BoxesFileWithBoxOutsideAndWidestRule) {
  Fixture f;
  std::string csv = "frame,x0,y0,x1,y1,score\n";
  for (int k = 0; k < 8; ++k) {
    const shle::Box& b = f.truth[k].box;
    if (k == 4) {
      csv += "4,2000,10,2100,40,0.9\n";  // off the image
      continue;
    }
    char line[200];
    std::snprintf(line, sizeof line, "%d,%.2f,%.2f,%.2f,%.2f,0.8\n%d,10,300,630,350,0.95\n", k, b.x0, b.y0, b.x1,
                  b.y1, k);
    csv += line;
  }
  shletest::write_text(f.dir / "boxes.csv", csv);
  shle::Sequence s = shle::scan_sequence(f.seq);
  shleapp::PngFrameLoader loader;
  shle::BoxesFileSource src(f.dir / "boxes.csv", s.frames.size());
  shle::SequenceRun run = shle::run_sequence(s, f.cal, src, loader, {});
  EXPECT_EQ(run.frames[0].box_source, "boxes-file");
  EXPECT_EQ(run.frames[0].box.x0, std::round(f.truth[0].box.x0 * 100) / 100);  // the paper rule drops the low box
  EXPECT_TRUE(has_problem(run.frames[4], "box lies outside the 640x360 disparity map"));
  EXPECT_FALSE(run.frames[4].stage2.has_height);
  EXPECT_EQ(run.frames_used, 7u);
  shle::PipelineOptions widest;
  widest.box_rule.rule = shle::BoxRule::Widest;
  run = shle::run_sequence(s, f.cal, src, loader, widest);
  EXPECT_EQ(run.frames[0].box.x0, 10);  // the wide low box
}

// A boxes CSV accepts x1 == x0 and y1 == y0 (only x1 < x0 is malformed): such a
// box reaches the tracker and stage 2, which must report it, not crash.
TEST(Pipeline, ZeroSizedBoxesFromCsv) {
  Fixture f;
  std::string csv = "frame,x0,y0,x1,y1,score\n";
  for (int k = 0; k < 8; ++k) {
    const shle::Box& b = f.truth[k].box;
    char line[200];
    if (k == 2 || k == 5)  // zero width
      std::snprintf(line, sizeof line, "%d,%.2f,%.2f,%.2f,%.2f,0.9\n", k, b.x0, b.y0, b.x0, b.y1);
    else if (k == 3)  // zero height: the extension still gives rows
      std::snprintf(line, sizeof line, "%d,%.2f,%.2f,%.2f,%.2f,0.9\n", k, b.x0, b.y0, b.x1, b.y0);
    else
      std::snprintf(line, sizeof line, "%d,%.2f,%.2f,%.2f,%.2f,0.9\n", k, b.x0, b.y0, b.x1, b.y1);
    csv += line;
  }
  shletest::write_text(f.dir / "boxes.csv", csv);
  shle::Sequence s = shle::scan_sequence(f.seq);
  shleapp::PngFrameLoader loader;
  shle::BoxesFileSource src(f.dir / "boxes.csv", s.frames.size());
  for (const char* tracker : {"ncc", "mil"}) {
    shle::PipelineOptions opt;
    opt.box_rule.rule = shle::BoxRule::Widest;  // keeps every lone box
    opt.tracker = tracker;
    shle::SequenceRun run = shle::run_sequence(s, f.cal, src, loader, opt);
    for (int k : {2, 5}) {
      EXPECT_TRUE(run.frames[k].has_box) << tracker;
      EXPECT_FALSE(run.frames[k].stage2.has_height) << tracker;
      EXPECT_TRUE(has_problem(run.frames[k], "box is empty")) << tracker;
    }
    EXPECT_TRUE(run.frames[3].has_box);
    EXPECT_GT(run.frames[3].stage2.window.height(), 0);
    EXPECT_TRUE(run.heights.has_scene_height);
    EXPECT_TRUE(std::isfinite(run.heights.scene_height));
  }
}

TEST(Pipeline, ImageDisparitySizeMismatch) {
  Fixture f(shleapp::SynthLayout::PlainPfm);
  shle::Sequence s = shle::scan_sequence(f.seq);
  ASSERT_EQ(s.frames[0].format, shle::DisparityFormat::Pfm);
  std::string pfm = "Pf\n10 10\n-1\n" + std::string(400, '\0');
  shletest::write_text(s.frames[0].disparity, pfm);
  shle::SequenceRun run = f.run();
  EXPECT_TRUE(has_problem(run.frames[0], "disparity is 10x10 but the image is 640x360"));
  EXPECT_FALSE(run.frames[0].stage2.has_height);
  EXPECT_TRUE(run.frames[1].stage2.has_height);
}

TEST(Pipeline, DeterministicAcrossRuns) {
  Fixture f;
  fs::remove(shle::scan_sequence(f.seq).frames[3].annotation);
  shle::SequenceRun a = f.run(), b = f.run();
  for (std::size_t i = 0; i < a.frames.size(); ++i) {
    EXPECT_EQ(a.frames[i].box.x0, b.frames[i].box.x0);
    EXPECT_EQ(a.frames[i].stage2.height, b.frames[i].stage2.height);
    EXPECT_EQ(a.frames[i].filtered, b.frames[i].filtered);
  }
}

TEST(Pipeline, BadOptionsThrow) {
  Fixture f;
  shle::PipelineOptions opt;
  opt.tracker = "kcf";
  EXPECT_ANY_THROW(f.run(opt));
  opt = {};
  opt.has_gt_height = true;
  opt.gt_height = -1;
  EXPECT_ANY_THROW(f.run(opt));
}

}  // namespace

// Issue 12, row 3: a 22000x22000 16-bit disparity PNG header used to be decoded
// (2.8 GB) before its size was checked; now the header alone is refused.
TEST(Pipeline, HugeDisparityPngIsRefusedFromItsHeader) {
  TempDir dir;
  auto crc32 = [](const std::uint8_t* p, std::size_t n) {
    std::uint32_t c = 0xFFFFFFFFu;
    for (std::size_t i = 0; i < n; ++i) {
      c ^= p[i];
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    }
    return c ^ 0xFFFFFFFFu;
  };
  auto be32 = [](std::vector<std::uint8_t>* v, std::uint32_t x) {
    for (int s = 24; s >= 0; s -= 8) v->push_back(static_cast<std::uint8_t>(x >> s));
  };
  auto chunk = [&](std::vector<std::uint8_t>* v, const char* type, const std::vector<std::uint8_t>& data) {
    be32(v, static_cast<std::uint32_t>(data.size()));
    const std::size_t start = v->size();
    v->insert(v->end(), type, type + 4);
    v->insert(v->end(), data.begin(), data.end());
    be32(v, crc32(v->data() + start, v->size() - start));
  };
  std::vector<std::uint8_t> png = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A};
  std::vector<std::uint8_t> ihdr;
  be32(&ihdr, 22000);
  be32(&ihdr, 22000);
  ihdr.insert(ihdr.end(), {16, 0, 0, 0, 0});  // 16-bit grey, deflate, no filter, no interlace
  chunk(&png, "IHDR", ihdr);
  chunk(&png, "IDAT", {0x78, 0x01, 0x03, 0x00, 0x00, 0x00, 0x00, 0x01});
  chunk(&png, "IEND", {});
  const std::string path = dir / "disp.png";
  shletest::write_bytes(path, png);
  const long before = testutil::peak_rss_kib();
  shleapp::PngFrameLoader loader;
  try {
    loader.load_png_disparity(path, 256);
    ADD_FAILURE() << "no limit error";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("disp.png: image is 22000x22000 (462 Mpx), above the limit of 64 Mpx"),
              std::string::npos)
        << e.what();
  }
  EXPECT_LT((testutil::peak_rss_kib() - before) / 1024, 100) << "the refusal committed memory";
}

TEST(Pipeline, FrameLoaderReadsSizesFromHeadersAndHoldsTheLimit) {
  TempDir dir;
  std::vector<std::uint8_t> rgb(64 * 48 * 3, 90);
  imageio::save_png((dir / "left.png"), rgb.data(), 64, 48, 3);
  // encode_png writes 8-bit files only: what the disparity check must refuse from the header.
  shleapp::PngFrameLoader loader;
  int w = 0, h = 0;
  ASSERT_TRUE(loader.image_size((dir / "left.png"), &w, &h));
  EXPECT_EQ(w, 64);
  EXPECT_EQ(h, 48);
  EXPECT_FALSE(loader.image_size((dir / "missing.png"), &w, &h));
  EXPECT_EQ(loader.load_image((dir / "left.png")).rgb, rgb);
  try {
    loader.load_png_disparity((dir / "left.png"), 256);
    ADD_FAILURE() << "an 8-bit RGB PNG was accepted as disparity";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("disparity PNG must be 16-bit single-channel, got 8-bit with 3 channel(s)"),
              std::string::npos)
        << e.what();
  }

  imageio::DecodeLimits small;
  small.max_pixels = 1000;
  shleapp::PngFrameLoader limited(small);
  ASSERT_TRUE(limited.image_size((dir / "left.png"), &w, &h));  // the header only: no limit
  EXPECT_EQ(w, 64);
  try {
    limited.load_image((dir / "left.png"));
    ADD_FAILURE() << "no limit error";
  } catch (const imageio::Error& e) {
    EXPECT_NE(std::string(e.what()).find("left.png: image is 64x48 (0.00293 Mpx), above the limit"), std::string::npos)
        << e.what();
  }
}
