// The shle command end to end on a synthetic sequence, and its failure modes.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "apps/common/image_io.h"
#include "tests/child_process.h"
#include "tests/shle/test_util.h"
#include "weights/safetensors.h"
#include "weights/json.h"

namespace {

namespace fs = std::filesystem;
using shletest::TempDir;

using shletest::Result;
using shletest::run;
using shletest::slurp;

// One synthetic sequence shared by the tests (written once).
const std::string& sequence() {
  static TempDir dir;
  static const std::string seq = [] {
    std::string s = dir / "seq";
    std::string cmd = std::string(SHLE_SYNTH_APP) + " --out '" + s + "' --frames 6 --seed 9 --quiet";
    if (std::system(cmd.c_str()) != 0) throw std::runtime_error("shle_synth failed");
    return s;
  }();
  return seq;
}

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::string cur;
  for (char c : s) {
    if (c == sep) {
      out.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  out.push_back(cur);
  return out;
}

TEST(ShleApp, WritesCsvSummaryAndPlot) {
  TempDir dir;
  const std::string out = dir / "out";
  Result r = run(std::string(SHLE_APP) + " --sequence '" + sequence() + "' --calib '" + sequence() +
                     "/calib.json' --gt-height 3.3 --out-dir '" + out + "'",
                 dir);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("scene height"), std::string::npos);
  EXPECT_NE(r.out.find("truth 3.300 m"), std::string::npos);
  std::vector<std::string> lines = split(slurp(out + "/frames.csv"), '\n');
  ASSERT_EQ(lines.size(), 8u);  // header, 6 frames, final newline
  EXPECT_EQ(lines[0], "frame,image,box_source,x0,y0,x1,y1,points,height_raw,height_filtered");
  for (int i = 1; i <= 6; ++i) {
    std::vector<std::string> f = split(lines[i], ',');
    ASSERT_EQ(f.size(), 10u) << lines[i];
    EXPECT_EQ(f[0], std::to_string(i - 1));
    EXPECT_EQ(f[2], "annotations");
    EXPECT_EQ(lines[i].find("nan"), std::string::npos);
    double h = std::stod(f[8]), hf = std::stod(f[9]);
    EXPECT_NEAR(h, 3.3, 0.4);
    EXPECT_NEAR(hf, 3.3, 0.4);
  }
  EXPECT_TRUE(lines[7].empty());
  json::Value s = json::parse(slurp(out + "/summary.json"), "summary.json");
  EXPECT_EQ(s.get("frames")->number(), 6);
  EXPECT_EQ(s.get("frames_used")->number(), 6);
  EXPECT_NEAR(s.get("scene_height")->number(), 3.3, 0.3);
  EXPECT_NEAR(s.get("he")->number(), s.get("scene_height")->number() - 3.3, 1e-9);
  EXPECT_TRUE(s.get("timings_ms")->is_object());
  imageio::Image plot = imageio::load(out + "/heights.png");
  EXPECT_EQ(plot.width, 1000);
  EXPECT_EQ(plot.height, 560);
  int files = 0;
  for (const auto& e : fs::directory_iterator(out)) {
    (void)e;
    ++files;
  }
  EXPECT_EQ(files, 3);  // no temporary files left behind
}

TEST(ShleApp, BoxesFileAndOptions) {
  TempDir dir;
  Result r = run(std::string(SHLE_APP) + " --sequence '" + sequence() + "' --calib '" + sequence() +
                     "/calib.json' --boxes '" + sequence() + "/detections.csv' --box-rule widest --kalman-compat" +
                     " --grid-step 0.5 --out-dir '" + (dir / "o") + "' --quiet",
                 dir);
  ASSERT_EQ(r.code, 0) << r.err;
  std::string csv = slurp(dir / "o/frames.csv");
  EXPECT_EQ(csv.find("nan"), std::string::npos);
  json::Value s = json::parse(slurp(dir / "o/summary.json"), "s");
  EXPECT_EQ(s.get("box_source")->str(), "boxes-file");
  EXPECT_EQ(s.get("detector"), nullptr);
  EXPECT_TRUE(s.get("options")->get("kalman_compat")->boolean());
  EXPECT_TRUE(s.get("gt_height")->is_null());
}

TEST(ShleApp, UsageAndInputErrors) {
  TempDir dir;
  const std::string app = SHLE_APP, seq = sequence();
  Result r = run(app + " --help", dir);
  EXPECT_EQ(r.code, 0);
  EXPECT_NE(r.out.find("--kalman-compat"), std::string::npos);
  EXPECT_NE(r.out.find("--max-pixels"), std::string::npos);
  r = run(app + " --sequence '" + seq + "' --calib x --max-pixels=-3", dir);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--max-pixels takes megapixels > 0"), std::string::npos) << r.err;
  r = run(app + " --sequence '" + seq + "'", dir);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--calib is required"), std::string::npos);
  r = run(app + " --sequence '" + seq + "' --calib x --box-rule best", dir);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("unknown box rule 'best'"), std::string::npos);
  r = run(app + " --sequence '" + seq + "' --calib x --lowest-n 0", dir);
  EXPECT_EQ(r.code, 2);
  r = run(app + " --sequence '" + (dir / "nope") + "' --calib '" + seq + "/calib.json' --out-dir '" + (dir / "o") + "'",
          dir);
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("no such sequence folder"), std::string::npos);
  shletest::write_text(dir / "bad.json", "{\"fx\": 1,}");
  r = run(app + " --sequence '" + seq + "' --calib '" + (dir / "bad.json") + "' --out-dir '" + (dir / "o") + "'",
          dir);
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("bad.json"), std::string::npos);
  shletest::write_text(dir / "b.csv", "0,1,2,3\n");
  r = run(app + " --sequence '" + seq + "' --calib '" + seq + "/calib.json' --boxes '" + (dir / "b.csv") +
              "' --out-dir '" + (dir / "o") + "'",
          dir);
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("b.csv: line 1: expected 6 fields"), std::string::npos);
  EXPECT_FALSE(fs::exists(dir / "o/frames.csv"));
}

TEST(ShleApp, SequenceWithoutAnyHeight) {
  TempDir dir;
  // Copy the sequence and zero every disparity: the run succeeds with no height.
  fs::copy(sequence(), dir / "seq", fs::copy_options::recursive);
  for (const auto& e : fs::directory_iterator(dir / "seq/disparity_images"))
    shletest::write_bytes(e.path().string(), std::vector<std::uint8_t>(2 * 1280 * 720, 0));
  Result r = run(std::string(SHLE_APP) + " --sequence '" + (dir / "seq") + "' --calib '" + (dir / "seq/calib.json") +
                     "' --gt-height 3.3 --out-dir '" + (dir / "o") + "'",
                 dir);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("no height"), std::string::npos);
  EXPECT_NE(r.err.find("no valid disparity in the box"), std::string::npos);
  std::vector<std::string> lines = split(slurp(dir / "o/frames.csv"), '\n');
  for (int i = 1; i <= 6; ++i) {
    std::vector<std::string> f = split(lines[i], ',');
    ASSERT_EQ(f.size(), 10u);
    EXPECT_EQ(f[8], "");
    EXPECT_EQ(f[9], "");
  }
  json::Value s = json::parse(slurp(dir / "o/summary.json"), "s");
  EXPECT_TRUE(s.get("scene_height")->is_null());
  EXPECT_TRUE(s.get("he")->is_null());
  EXPECT_TRUE(fs::exists(dir / "o/heights.png"));
}


// Seeded random weights of the fastest detector, written once by `synth`.
const std::string& detector_weights() {
  static TempDir dir;
  static const std::string path = [] {
    std::string w = dir / "det320.safetensors";
    std::string cmd = std::string(SYNTH_APP) + " --model fasterrcnn_mobilenet_v3_large_320_fpn --seed 3 --out '" + w +
                      "' > /dev/null";
    if (std::system(cmd.c_str()) != 0) throw std::runtime_error("synth failed");
    return w;
  }();
  return path;
}

std::string detector_cmd(const std::string& weights, const std::string& out_dir) {
  return std::string(SHLE_APP) + " --sequence '" + sequence() + "' --calib '" + sequence() +
         "/calib.json' --boxes detector --detector-model fasterrcnn_mobilenet_v3_large_320_fpn --detector-weights '" +
         weights + "' --out-dir '" + out_dir + "' --quiet";
}

bool no_outputs(const std::string& out_dir) {
  return !fs::exists(out_dir + "/frames.csv") && !fs::exists(out_dir + "/summary.json") &&
         !fs::exists(out_dir + "/heights.png");
}

TEST(ShleApp, DetectorBoxes) {
  TempDir dir;
  const std::string out = dir / "o";
  // Thresholds 0: untrained weights score anything; most frames should get a box.
  Result r = run(
      detector_cmd(detector_weights(), out) + " --detector-score 0 --min-score 0 --box-rule widest --threads 1", dir);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("shle: detector fasterrcnn_mobilenet_v3_large_320_fpn, 2 classes (device labels 1, "
                       "score > 0), weights " + detector_weights()),
            std::string::npos)
      << r.err;
  std::vector<std::string> lines = split(slurp(out + "/frames.csv"), '\n');
  ASSERT_EQ(lines.size(), 8u);
  int detector_frames = 0;
  for (int i = 1; i <= 6; ++i) {
    std::vector<std::string> f = split(lines[i], ',');
    ASSERT_EQ(f.size(), 10u) << lines[i];
    EXPECT_TRUE(f[2] == "detector" || f[2] == "tracker" || f[2].empty()) << lines[i];
    detector_frames += f[2] == "detector";
  }
  EXPECT_GT(detector_frames, 0) << slurp(out + "/frames.csv");
  json::Value s = json::parse(slurp(out + "/summary.json"), "s");
  EXPECT_EQ(s.get("box_source")->str(), "detector");
  const json::Value* d = s.get("detector");
  ASSERT_NE(d, nullptr);
  EXPECT_EQ(d->get("model")->str(), "fasterrcnn_mobilenet_v3_large_320_fpn");
  EXPECT_EQ(d->get("weights")->str(), detector_weights());
  EXPECT_EQ(d->get("classes")->number(), 2);
  EXPECT_EQ(d->get("score_threshold")->number(), 0);
}

// detectron2's model by name: labels are 0-based (0 parses), and weights of another
// architecture stop the run naming the file and the first tensor it lacks.
TEST(ShleApp, Detectron2DetectorModel) {
  TempDir dir;
  const std::string out = dir / "o";
  const std::string cmd = std::string(SHLE_APP) + " --sequence '" + sequence() + "' --calib '" + sequence() +
                          "/calib.json' --boxes detector --detector-model detectron2_faster_rcnn_r50_fpn "
                          "--detector-labels 0 --detector-weights '" + detector_weights() + "' --out-dir '" + out +
                          "' --quiet";
  Result r = run(cmd, dir);
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find(detector_weights() + ": missing tensor 'backbone.bottom_up.stem.conv1.weight'"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_TRUE(no_outputs(out));
  r = run(cmd + " --detector-labels x", dir);
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("detectron2's 0-based classes"), std::string::npos) << r.err;
}

TEST(ShleApp, DetectorErrors) {
  TempDir dir;
  const std::string app = SHLE_APP, seq = sequence(), out = dir / "o";
  const std::string base = app + " --sequence '" + seq + "' --calib '" + seq + "/calib.json' --out-dir '" + out + "'";
  Result r = run(base + " --boxes detector", dir);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--boxes detector needs --detector-weights"), std::string::npos) << r.err;
  r = run(base + " --detector-weights w.safetensors", dir);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--detector-weights needs --boxes detector"), std::string::npos) << r.err;
  r = run(base + " --boxes detector --detector-weights w --detector-model fasterrcnn_vgg", dir);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--detector-model must be"), std::string::npos) << r.err;
  r = run(base + " --boxes detector --detector-weights w --detector-score 1.5", dir);
  EXPECT_EQ(r.code, 2);
  r = run(base + " --boxes detector --detector-weights w --detector-labels 1,x", dir);
  EXPECT_EQ(r.code, 2);
  r = run(base + " --boxes detector --detector-weights w --threads 0", dir);
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(no_outputs(out));

  // Missing and garbage files: one line naming the file, exit 1, no output.
  const std::string missing = dir / "missing.safetensors";
  r = run(detector_cmd(missing, out), dir);
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(r.err.rfind("shle: " + missing + ": ", 0), 0u) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_TRUE(no_outputs(out));
  shletest::write_text(dir / "garbage.safetensors", "this is not a safetensors file at all");
  r = run(detector_cmd(dir / "garbage.safetensors", out), dir);
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(r.err.rfind("shle: " + (dir / "garbage.safetensors") + ": ", 0), 0u) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_TRUE(no_outputs(out));

  // Weights of another architecture name a tensor.
  const std::string convnext = dir / "convnext.safetensors";
  const std::string make_convnext =
      std::string(SYNTH_APP) + " --model convnext_tiny --out '" + convnext + "' > /dev/null";
  ASSERT_EQ(std::system(make_convnext.c_str()), 0);
  r = run(detector_cmd(convnext, out), dir);
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(r.err.rfind("shle: " + convnext + ": missing tensor 'roi_heads.box_predictor.cls_score.weight'", 0), 0u)
      << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_TRUE(no_outputs(out));

  // A label the weights do not hold.
  r = run(detector_cmd(detector_weights(), out) + " --detector-labels 1,2", dir);
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("label 2 asked for, but the weights hold 2 classes"), std::string::npos) << r.err;
  EXPECT_TRUE(no_outputs(out));
}

}  // namespace

// Issue 12, finding 11: a bad height in benchmark.csv names the file, the line and the
// value (it was "shle_eval: stod").
TEST(ShleApp, EvalBadHeightNamesFileLineAndValue) {
  TempDir dir;
  std::filesystem::create_directories(dir / "bench");
  for (const std::string h : {"tall", "1e999", "-2", "3.3x", "nan"}) {
    std::ofstream(dir / "bench/benchmark.csv") << "scene,device,height\ns1,bar," << h << "\n";
    Result r = run(std::string(SHLE_EVAL_APP) + " --benchmark '" + (dir / "bench") + "'", dir);
    EXPECT_EQ(r.code, 1) << h << ": " << r.err;
    EXPECT_NE(r.err.find("benchmark.csv: line 2: height '" + h + "' is not a positive finite number"), std::string::npos)
        << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
}

// Issue 12, rows 8-10 through the app: one line, exit code, no output written.
TEST(ShleApp, HostileParametersAndSpecialFiles) {
  TempDir dir;
  const std::string app = SHLE_APP, seq = sequence(), out = dir / "o";
  Result r = run(app + " --sequence '" + seq + "' --calib '" + seq + "/calib.json' --grid-step 1e-9 --out-dir '" +
                     out + "'",
                 dir);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("KDE grid step must be a number in [0.001, 1000] metres"), std::string::npos) << r.err;
  const std::string fifo = dir / "calib.fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  // `timeout` turns a regression (open() blocking on the FIFO) into a failure.
  for (const std::string& args : {" --calib '" + fifo + "'", " --calib '" + seq + "/calib.json' --boxes '" + fifo + "'"}) {
    r = run("timeout 20 " + app + " --sequence '" + seq + "'" + args + " --out-dir '" + out + "'", dir);
    EXPECT_EQ(r.code, 1) << args;
    EXPECT_EQ(r.err, "shle: " + fifo + ": is a pipe (FIFO), expected a regular file\n") << args;
  }
  shletest::write_text(dir / "huge.json",
                       "{\"fx\": 700, \"fy\": 700, \"cx\": 0, \"cy\": 0, \"bf\": 240, \"width\": 65535, "
                       "\"height\": 65535}");
  r = run(app + " --sequence '" + seq + "' --calib '" + (dir / "huge.json") + "' --out-dir '" + out + "'", dir);
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("huge.json: 'width' x 'height' is 65535x65535, above the limit of 256 Mpx"), std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(out + "/frames.csv"));
  EXPECT_FALSE(fs::exists(out + "/summary.json"));
}

// Issue 12, row 10: `synth --range nan,1` used to write an all-NaN input and exit 0.
TEST(SynthApp, NonFiniteRangeIsAUsageError) {
  TempDir dir;
  for (const char* range : {"nan,1", "0,inf", "2,1", "-1e308,1e308"}) {
    Result r = run(std::string(SYNTH_APP) + " --shape 1,3,4,4 --range " + range + " --out '" + (dir / "x.st") + "'",
                   dir);
    EXPECT_EQ(r.code, 2) << range;
    EXPECT_NE(r.err.find("--range LO,HI needs finite numbers with LO <= HI"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir / "x.st")) << range;
  }
}

// Issue 12 item 5, finding 6: --calib OUT/summary.json --out-dir OUT would replace the
// calibration with the summary; refused in one line before anything is written.
TEST(ShleApp, CalibrationInTheOutputFolderIsNotOverwritten) {
  TempDir dir;
  const std::string out = dir / "o";
  fs::create_directories(out);
  fs::copy_file(sequence() + "/calib.json", out + "/summary.json");
  const std::string before = slurp(out + "/summary.json");
  Result r = run(std::string(SHLE_APP) + " --sequence '" + sequence() + "' --calib '" + out + "/summary.json' --out-dir '" +
                     out + "' --quiet",
                 dir);
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(r.err, "shle: output " + out + "/summary.json would overwrite the calibration " + out + "/summary.json\n");
  EXPECT_EQ(slurp(out + "/summary.json"), before);
  EXPECT_FALSE(fs::exists(out + "/frames.csv"));
  EXPECT_FALSE(fs::exists(out + "/heights.png"));
  EXPECT_EQ(std::distance(fs::directory_iterator(out), {}), 1);
}

// Issue 12 item 5, finding 7: shle interrupted (SIGINT as soon as a temporary appears
// in OUT) leaves the previous run's three files or the new run's three, never a mix,
// and no temporary. Consecutive runs differ (--gt-height and --extend-top alternate)
// so every file of a new set differs from the old one. A run that finishes before the
// signal must have replaced the whole set; it is tried again (a few times at most).
TEST(ShleApp, InterruptedRunLeavesOneRunsSet) {
  TempDir dir;
  const std::string out = dir / "o";
  const std::vector<std::string> files = {out + "/frames.csv", out + "/summary.json", out + "/heights.png"};
  auto args = [&](int k) {
    std::vector<std::string> a = {SHLE_APP, "--sequence", sequence(), "--calib", sequence() + "/calib.json",
                                  "--out-dir", out, "--quiet", "--extend-top", k % 2 ? "5" : "20"};
    if (k % 2) a.insert(a.end(), {"--gt-height", "3.3"});
    return a;
  };
  pid_t first = testproc::spawn(args(0));
  ASSERT_GT(first, 0);
  int status = testproc::wait_for(first, 300);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << status;
  bool interrupted = false;
  for (int k = 1; k <= 6 && !interrupted; ++k) {
    std::vector<std::string> old;
    for (const std::string& f : files) old.push_back(slurp(f));
    pid_t pid = testproc::spawn(args(k));
    ASSERT_GT(pid, 0);
    if (testproc::poll_until(pid, [&] { return !testproc::temporaries_under(out).empty(); }, 300)) ::kill(pid, SIGINT);
    status = testproc::wait_for(pid, 300);
    ASSERT_NE(status, -1) << "shle did not end";
    interrupted = WIFSIGNALED(status) && WTERMSIG(status) == SIGINT;
    EXPECT_EQ(testproc::temporaries_under(out), std::vector<std::string>{});
    int unchanged = 0;
    for (std::size_t i = 0; i < files.size(); ++i) {
      ASSERT_TRUE(fs::exists(files[i])) << files[i];
      unchanged += slurp(files[i]) == old[i];
    }
    EXPECT_TRUE(unchanged == 0 || unchanged == 3) << unchanged << " of 3 files are the previous run's";
    if (!interrupted) {
      EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << status;
      EXPECT_EQ(unchanged, 0);
    }
  }
  if (!interrupted) std::cout << "note: shle finished before SIGINT in every attempt\n";
}

// Issue 12 item 5, finding 7: SIGINT while synth writes its 111 MB of weights leaves
// the previous file (here a marker) or the complete new one, never a temporary. The
// signal goes out when the temporary appears; should synth finish first, the file must
// be whole, and it is tried again.
TEST(ShleApp, InterruptedSynthLeavesNoTemporary) {
  TempDir dir;
  const std::string w = dir / "w.safetensors";
  bool interrupted = false;
  for (int attempt = 0; attempt < 3 && !interrupted; ++attempt) {
    shletest::write_text(w, "previous");
    pid_t pid = testproc::spawn({SYNTH_APP, "--model", "convnext_tiny", "--out", w});
    ASSERT_GT(pid, 0);
    if (testproc::poll_until(pid, [&] { return !testproc::temporaries_under(dir.path()).empty(); }, 300))
      ::kill(pid, SIGINT);
    const int status = testproc::wait_for(pid, 300);
    ASSERT_NE(status, -1) << "synth did not end";
    interrupted = WIFSIGNALED(status) && WTERMSIG(status) == SIGINT;
    EXPECT_EQ(testproc::temporaries_under(dir.path()), std::vector<std::string>{});
    const std::string now = slurp(w);
    if (now != "previous") {
      EXPECT_GT(now.size(), 100u << 20);
      weights::SafeTensors st = weights::SafeTensors::load(w);  // complete and valid
      EXPECT_TRUE(st.has("features.0.0.weight"));
    }
    if (!interrupted) {
      EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << status;
    }
  }
  if (!interrupted) std::cout << "note: synth finished before SIGINT in every attempt\n";
}
