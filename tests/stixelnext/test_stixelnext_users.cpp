// Issue 14, "StixelNExT++ as its users have it": self-describing model files
// (export.py --preset/--meta, stixelnext --preset, the V1/V3 warning, a declared
// head contradicting the tensors), the authors' calibration files, --points
// against pyStixel-lib's point cloud, the embedded image, --bev-fit.
#include <filesystem>
#include <map>

#include "stixel/image_header.h"
#include "stixel/model_file.h"
#include "stixel/stx1.h"
#include "tests/stixelnext/cli_fixture.h"
#include "weights/safetensors.h"

namespace {

using stixelnext_test::slurp;
using V = nn::StixelHeadVariant;

class StixelnextUsers : public stixelnext_test::StixelnextCli {
 protected:
  // Runs a python script of the repository; returns its exit status, output in py_.
  int python(const std::string& script_and_args) {
    const std::string cmd = std::string(ROADNN_PYTHON) + " " + ROADNN_SOURCE_DIR + "/" + script_and_args + " >" +
                            path("py.out") + " 2>&1";
    const int status = std::system(cmd.c_str());
    py_ = slurp(path("py.out"));
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }
  int count(const std::string& text, const std::string& what) {
    int n = 0;
    for (std::size_t p = text.find(what); p != std::string::npos; p = text.find(what, p + 1)) ++n;
    return n;
  }
  std::string py_;
};

// Done means 1: a file exported with a preset runs with no flag and gives the same
// stixels as the flags did; the preset tables of export.py and the library agree.
TEST_F(StixelnextUsers, PresetFileRunsWithoutFlagsLikeTheFlags) {
  write_weights("plain.safetensors", V::V4, {});
  const std::string common = " --threshold 0.3 --format csv " + path("img.png");
  ASSERT_EQ(run("--weights " + path("plain.safetensors") +
                " --input-size 1200x1920 --columns 120 --stixel-width 16 --normalization imagenet" + common), 0)
      << err_;
  const std::string by_flags = slurp(path("out/img.csv"));
  ASSERT_GT(count(by_flags, "\n"), 1) << "no stixels to compare";

  for (const std::string& preset : stixel::preset_names()) {
    ASSERT_EQ(python("weights/export.py " + path("plain.safetensors") + " " + path(preset + ".safetensors") +
                     " --preset " + preset), 0) << py_;
    const auto exported = weights::SafeTensors::load(path(preset + ".safetensors"));
    std::map<std::string, std::string> want;
    ASSERT_TRUE(stixel::preset_metadata(preset, &want));
    for (const auto& [key, value] : want) {
      auto it = exported.metadata().find(key);
      ASSERT_NE(it, exported.metadata().end()) << preset << ": export.py did not write " << key;
      EXPECT_EQ(it->second, value) << preset << " " << key << ": export.py and stixel/model_file.cpp disagree";
    }
  }
  ASSERT_EQ(run("--weights " + path("coopscenes.safetensors") + common), 0) << err_;
  EXPECT_EQ(slurp(path("out/img.csv")), by_flags);
  EXPECT_EQ(err_.find("warning"), std::string::npos) << err_;
  // The same from a checkpoint as the authors' train.py saves it, {"model_state_dict": ...}
  // with DDP's "module." prefix.
  write_text("to_pth.py",
             "import sys, torch\n"
             "sys.path.insert(0, sys.argv[1] + '/weights')\n"
             "import safetensors_io\n"
             "t, _ = safetensors_io.load(sys.argv[2])\n"
             "torch.save({'epoch': 3, 'model_state_dict': {'module.' + k: torch.from_numpy(v.copy()) "
             "for k, v in t.items()}}, sys.argv[3])\n");
  const std::string cmd = std::string(ROADNN_PYTHON) + " " + path("to_pth.py") + " " + ROADNN_SOURCE_DIR + " " +
                          path("plain.safetensors") + " " + path("best.pth") + " >" + path("py.out") + " 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << slurp(path("py.out"));
  ASSERT_EQ(python("weights/export.py " + path("best.pth") + " " + path("from_pth.safetensors") +
                   " --preset coopscenes --meta stixelnext.head=v4"), 0) << py_;
  ASSERT_EQ(run("--weights " + path("from_pth.safetensors") + common), 0) << err_;
  EXPECT_EQ(slurp(path("out/img.csv")), by_flags);
  EXPECT_EQ(err_.find("warning"), std::string::npos) << err_;
  ASSERT_EQ(run("--weights " + path("plain.safetensors") + " --preset coopscenes" + common), 0) << err_;
  EXPECT_EQ(slurp(path("out/img.csv")), by_flags);
  // The flags still win over the file's settings.
  ASSERT_EQ(run("--weights " + path("coopscenes.safetensors") + " --input-size 64x96 --columns 12 --stixel-width 8" +
                common), 0) << err_;
  EXPECT_NE(slurp(path("out/img.csv")), by_flags);
  EXPECT_EQ(run("--weights " + path("plain.safetensors") + " --preset kitti" + common), 2);
  EXPECT_NE(err_.find("--preset must be waymo or coopscenes"), std::string::npos) << err_;
}

// Done means 1: tensors that fit V1 and V3 with nothing saying which: one warning
// per run (not per image) naming both and the fix; none once the head is named.
TEST_F(StixelnextUsers, V1V3AmbiguousFileWarnsOncePerRun) {
  write_weights("v13.safetensors", V::V1);
  std::filesystem::copy_file(path("img.png"), path("img2.png"));
  const std::string images = " " + path("img.png") + " " + path("img2.png");
  ASSERT_EQ(run("--weights " + path("v13.safetensors") + images), 0) << err_;
  EXPECT_EQ(count(err_, "warning"), 1) << err_;
  for (const char* must : {"V1", "V3", "--head v1", "stixelnext.head=v1", "v13.safetensors"})
    EXPECT_NE(err_.find(must), std::string::npos) << must << " missing in: " << err_;
  ASSERT_EQ(run("--weights " + path("v13.safetensors") + " --head v3" + images), 0) << err_;
  EXPECT_EQ(err_.find("warning"), std::string::npos) << err_;
  write_weights("v3.safetensors", V::V1,
                {{"stixelnext.input_height", "64"}, {"stixelnext.input_width", "96"}, {"stixelnext.head", "v3"}});
  ASSERT_EQ(run("--weights " + path("v3.safetensors") + images), 0) << err_;
  EXPECT_EQ(err_.find("warning"), std::string::npos) << err_;
}

// Done means 1: a file that declares a head its tensors contradict fails, naming
// the key and the tensor, before any output.
TEST_F(StixelnextUsers, DeclaredHeadContradictingTheTensorsFails) {
  struct Case {
    V tensors;
    const char* declared;
    const char* tensor;
  } cases[] = {{V::V1, "v4", "classifier.local_mixing.depthwise.weight is missing"},
               {V::V4, "v1", "classifier.attention_layer.query_layer.weight is missing"},
               {V::V1, "v2", "classifier.channel_reduce.weight is [192, 56, 1, 1] where a v2 head needs [192, 28, 1, 1]"},
               {V::V2, "v0", "classifier.attention_layer.query_layer.weight is present"}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.declared);
    write_weights("bad.safetensors", c.tensors,
                  {{"stixelnext.input_height", "64"}, {"stixelnext.input_width", "96"},
                   {"stixelnext.head", c.declared}});
    EXPECT_EQ(run("--weights " + path("bad.safetensors") + " " + path("img.png")), 1);
    expect_error_line(std::string("metadata stixelnext.head=") + c.declared + " contradicts the tensors");
    EXPECT_NE(err_.find(c.tensor), std::string::npos) << err_;
    EXPECT_FALSE(exists("out/img.stx1"));
  }
}

// Done means 2: the authors' {fx, fy, cx, cy} per image, each .stx1 carrying the
// calibration its image used; one file for all works too.
TEST_F(StixelnextUsers, AuthorsCalibrationPerImage) {
  std::filesystem::copy_file(path("img.png"), path("img2.png"));
  write_text("img.json", R"({"fx": 80, "fy": 82, "cx": 47.5, "cy": 31.5})");
  write_text("img2.json", R"({"fx": 120.5, "fy": 121, "cx": 48, "cy": 30, "note": "ignored, as their loader does"})");
  ASSERT_EQ(run("--weights " + path("w.safetensors") + " --calib-per-image --cluster --points csv " + path("img.png") +
                " " + path("img2.png")), 0) << err_;
  const std::vector<float> identity = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  const auto a = stixel::read_stx1(path("out/img.stx1"));
  const auto b = stixel::read_stx1(path("out/img2.stx1"));
  EXPECT_EQ(a.context.calibration.K, (std::vector<float>{80, 0, 47.5f, 0, 82, 31.5f, 0, 0, 1}));
  EXPECT_EQ(b.context.calibration.K, (std::vector<float>{120.5f, 0, 48, 0, 121, 30, 0, 0, 1}));
  EXPECT_EQ(a.context.calibration.T, identity);
  EXPECT_EQ(b.context.calibration.T, identity);
  EXPECT_TRUE(exists("out/img_points.csv"));
  ASSERT_EQ(run("--weights " + path("w.safetensors") + " --calib " + path("img2.json") + " " + path("img.png")), 0)
      << err_;
  EXPECT_EQ(stixel::read_stx1(path("out/img.stx1")).context.calibration.K, b.context.calibration.K);
  EXPECT_EQ(run("--weights " + path("w.safetensors") + " --calib " + path("img.json") + " --calib-per-image " +
                path("img.png")), 2);
}

// Done means 2: malformed calibration files give one line naming the file and
// no output file, per image and for --calib.
TEST_F(StixelnextUsers, MalformedCalibrationFilesFailWithOneLine) {
  struct Case {
    const char* text;  // nullptr: no file at all
    const char* problem;
  } cases[] = {{R"({"fx": 80, "fy": 80, "cx": 47.5})", "missing \"cy\""},
               {R"({"fx": "80", "fy": 80, "cx": 47.5, "cy": 31.5})", "\"fx\" must be a number"},
               {R"({"fx": NaN, "fy": 80, "cx": 47.5, "cy": 31.5})", "line 1"},
               {R"({"fx": 80, "fy": 80, "cx": 1e39, "cy": 31.5})", "\"cx\" is not a finite float32 number"},
               {R"({"fx": -80, "fy": 80, "cx": 47.5, "cy": 31.5})", "focal lengths must be positive"},
               {R"({"fx": 80, "fy": 0, "cx": 47.5, "cy": 31.5})", "focal lengths must be positive"},
               {R"([80, 80, 47.5, 31.5])", "expected a JSON object"},
               {nullptr, "img.json"}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.text ? c.text : "(no file)");
    std::filesystem::remove(path("img.json"));
    if (c.text) write_text("img.json", c.text);
    std::filesystem::remove_all(path("out"));
    EXPECT_EQ(run("--weights " + path("w.safetensors") + " --calib-per-image --points ply " + path("img.png")), 1);
    expect_error_line(path("img.json") + ": ");
    EXPECT_NE(err_.find(c.problem), std::string::npos) << err_;
    EXPECT_FALSE(exists("out/img.stx1"));
    EXPECT_FALSE(exists("out/img_points.ply"));
    if (!c.text) continue;
    EXPECT_EQ(run("--weights " + path("w.safetensors") + " --calib " + path("img.json") + " " + path("img.png")), 1);
    expect_error_line(path("img.json") + ": ");
    EXPECT_FALSE(exists("out/img.stx1"));
  }
}

// Done means 3: by default the .stx1 embeds the input file itself and carries
// every field pyStixel-lib's reader and draw_stixels_on_image need (decoded with
// python3-protobuf); the --points PLY is pyStixel-lib's convert_to_point_cloud of
// that world within 1e-5 m, with its colours, stixel indices and cluster labels.
TEST_F(StixelnextUsers, DefaultStx1AndPointsAreWhatPyStixelLibReads) {
  ASSERT_EQ(run("--weights " + path("w.safetensors") + " --calib " + path("cam.json") +
                " --threshold 0.2 --cluster --points ply " + path("img.png")), 0) << err_;
  const auto world = stixel::read_stx1(path("out/img.stx1"));
  EXPECT_EQ(std::string(world.image.begin(), world.image.end()), slurp(path("img.png")));
  ASSERT_EQ(python("tests/reference/stixel_pystixel_check.py --pb-dir " + path("pb") + " --input " +
                   path("out/img.stx1") + " --points " + path("out/img_points.ply") + " --expect-image " +
                   path("img.png")), 0) << py_;
  EXPECT_NE(py_.find("points: "), std::string::npos) << py_;
  EXPECT_EQ(py_.find("points: 0 compared"), std::string::npos) << py_;

  // The CSV holds the same points.
  ASSERT_EQ(run("--weights " + path("w.safetensors") + " --calib " + path("cam.json") +
                " --threshold 0.2 --cluster --points csv " + path("img.png")), 0) << err_;
  const std::string csv = slurp(path("out/img_points.csv"));
  EXPECT_EQ(csv.rfind("x,y,z,r,g,b,stixel,cluster\n", 0), 0u) << csv.substr(0, 80);
  const std::string ply = slurp(path("out/img_points.ply"));
  const std::size_t at = ply.find("element vertex ");
  ASSERT_NE(at, std::string::npos);
  EXPECT_EQ(count(csv, "\n") - 1, std::stoi(ply.substr(at + 15)));

  // --no-embed-image leaves it out.
  ASSERT_EQ(run("--weights " + path("w.safetensors") + " --no-embed-image " + path("img.png")), 0) << err_;
  EXPECT_TRUE(stixel::read_stx1(path("out/img.stx1")).image.empty());
}

// A resized input embeds what pyStixel-lib expects: the image in the stixels'
// pixel frame (the network input, the calibration's size), as a PNG.
TEST_F(StixelnextUsers, ResizedInputEmbedsTheNetworkSizeImage) {
  std::vector<std::uint8_t> px(50 * 70 * 3);
  for (std::size_t i = 0; i < px.size(); ++i) px[i] = static_cast<std::uint8_t>((i * 13) % 256);
  imageio::save_png(path("small.png"), px.data(), 70, 50, 3);
  write_text("small.json", R"({"fx": 60, "fy": 60, "cx": 35, "cy": 25})");
  ASSERT_EQ(run("--weights " + path("w.safetensors") + " --calib-per-image --threshold 0.2 --points ply " +
                path("small.png")), 0) << err_;
  const auto world = stixel::read_stx1(path("out/small.stx1"));
  int w = 0, h = 0;
  ASSERT_TRUE(stixel::image_size(world.image.data(), world.image.size(), &w, &h));
  EXPECT_EQ(stixel::image_format(world.image.data(), world.image.size()), stixel::ImageFormat::Png);
  EXPECT_EQ(w, 96);
  EXPECT_EQ(h, 64);
  ASSERT_EQ(python("tests/reference/stixel_pystixel_check.py --pb-dir " + path("pb") + " --input " +
                   path("out/small.stx1") + " --points " + path("out/small_points.ply")), 0) << py_;
}

TEST_F(StixelnextUsers, BevFitDrawsTheDataWindow) {
  ASSERT_EQ(run("--weights " + path("w.safetensors") + " --calib " + path("cam.json") + " --threshold 0.2 --bev-fit " +
                path("img.png")), 0) << err_;
  imageio::Image bev = imageio::load(path("out/img_bev.png"), 3);
  ASSERT_EQ(bev.width, 1024);
  ASSERT_EQ(bev.height, 1024);
  std::size_t drawn = 0;
  for (std::size_t p = 0; p < bev.u8.size(); p += 3)
    drawn += !(bev.u8[p] == 20 && bev.u8[p + 1] == 20 && bev.u8[p + 2] == 20);
  EXPECT_GT(drawn, 100u);
  // The fitted window reaches the canvas edges on both axes.
  bool left = false, right = false;
  for (int y = 0; y < 1024; ++y) {
    left = left || bev.u8[static_cast<std::size_t>(y) * 1024 * 3] != 20;
    right = right || bev.u8[(static_cast<std::size_t>(y) * 1024 + 1023) * 3] != 20;
  }
  EXPECT_TRUE(left && right);
}

TEST_F(StixelnextUsers, PointsOptionNeedsACalibrationAndAFormat) {
  EXPECT_EQ(run("--weights " + path("w.safetensors") + " --points ply " + path("img.png")), 2);
  EXPECT_NE(err_.find("--points need"), std::string::npos) << err_;
  EXPECT_EQ(run("--weights " + path("w.safetensors") + " --calib " + path("cam.json") + " --points xyz " +
                path("img.png")), 2);
  EXPECT_NE(err_.find("--points must be ply or csv"), std::string::npos) << err_;
}

}  // namespace
