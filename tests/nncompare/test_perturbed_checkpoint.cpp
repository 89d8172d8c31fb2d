// Issue 16, "done means" 2: two scripts/torch_dump.py dumps of a ConvNeXt-Tiny checkpoint,
// one with features.3.1.block.3.weight scaled by 1.01 (fixture ref_perturbed_dump_ref).
// nncompare must fail on the first module downstream of that tensor, the pointwise
// Linear features.3.1.block.3 itself, and pass every tensor before it.
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <string>

#include "tests/nncompare/nncompare_run.h"
#include "weights/json.h"

namespace {

std::string ref_file(const std::string& f) { return std::string(ROADNN_REF_DIR) + "/" + f; }

TEST(PerturbedCheckpoint, NncompareNamesTheFirstModuleDownstream) {
  for (const char* f : {"perturbed_changed.dump.safetensors", "perturbed_original.dump.safetensors"})
    ASSERT_TRUE(std::ifstream(ref_file(f)).good())
        << ref_file(f) << " is missing: its generator (ctest fixture ref_perturbed_dump_ref, scripts/torch_dump.py) "
        << "failed or did not run; it needs python3-torch and python3-torchvision for /usr/bin/python3";
  char tmpl[] = "/tmp/nncompare_perturbed_XXXXXX";
  ASSERT_NE(mkdtemp(tmpl), nullptr);
  const std::string dir = tmpl;
  nncompare_test::Result r = nncompare_test::run(
      dir, ref_file("perturbed_changed.dump.safetensors") + " " + ref_file("perturbed_original.dump.safetensors") +
               " --rtol 1e-4 --json");
  ASSERT_EQ(r.code, 1) << r.out << r.err;
  const json::Value report = json::parse(r.out, "nncompare --json");
  EXPECT_EQ(report.get("first_failure")->str(), "features.3.1.block.3");

  // Network order: everything before the perturbed layer is bitwise equal (same
  // weights, same input, same program), so it passes at any tolerance.
  const auto& tensors = report.get("tensors")->array();
  std::size_t before = 0;
  bool reached = false;
  for (const json::Value& t : tensors) {
    const std::string name = t.get("name")->str();
    if (name == "features.3.1.block.3") {
      reached = true;
      EXPECT_TRUE(t.get("failed")->boolean());
      EXPECT_GT(t.get("max_rel_diff")->number(), 1e-3) << "a 1% weight change shows";
      break;
    }
    ++before;
    EXPECT_EQ(t.get("status")->str(), "ok") << name;
    EXPECT_EQ(t.get("max_abs_diff")->number(), 0.0) << name;
  }
  EXPECT_TRUE(reached);
  // Stem, stage 1, downsample, block features.3.0 and block 1's first three modules.
  EXPECT_GT(before, 30u);
  // Everything after it depends on it: the final stage output fails too.
  bool last_failed = false;
  for (const json::Value& t : tensors)
    if (t.get("name")->str() == "features.7") last_failed = t.get("failed")->boolean();
  EXPECT_TRUE(last_failed);

  // The same files at --rtol 0.05 pass: the tolerance decides.
  r = nncompare_test::run(dir, ref_file("perturbed_changed.dump.safetensors") + " " +
                                   ref_file("perturbed_original.dump.safetensors") + " --rtol 0.05");
  EXPECT_EQ(r.code, 0) << r.out;
  std::system(("rm -rf " + dir).c_str());
}

}  // namespace

namespace {

// The workflow across the two sides: nnrun's output file against the torch dump of the
// same weights and input. nnrun --output writes 'features', the name torch_dump.py's
// module `features` has, so nncompare compares exactly that tensor and lists the rest
// as only in the reference.
TEST(PerturbedCheckpoint, NnrunOutputMatchesTheTorchDumpThroughNncompare) {
  char tmpl[] = "/tmp/nncompare_nnrun_XXXXXX";
  ASSERT_NE(mkdtemp(tmpl), nullptr);
  const std::string dir = tmpl;
  for (const char* w : {"perturbed_weights", "perturbed_weights_changed"}) {
    const std::string y = dir + "/" + w + ".y.safetensors";
    const std::string cmd = std::string(NNRUN_PATH) + " --model convnext_tiny --weights " + ref_file(std::string(w) + ".safetensors") +
                            " --input " + ref_file("perturbed_input.safetensors") + " --output " + y + " --quiet";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
    nncompare_test::Result r = nncompare_test::run(dir, y + " " + ref_file("perturbed_original.dump.safetensors") + " --json");
    const json::Value report = json::parse(r.out, "nncompare --json");
    EXPECT_EQ(report.get("compared")->number(), 1) << r.out;
    EXPECT_EQ(report.get("only_in_a")->number(), 0) << r.out;
    EXPECT_GT(report.get("only_in_reference")->number(), 100) << r.out;
    if (std::string(w) == "perturbed_weights") {
      EXPECT_EQ(r.code, 0) << r.out;  // the engine within 1e-4 of PyTorch's max|features|
      EXPECT_TRUE(report.get("first_failure")->is_null());
    } else {
      EXPECT_EQ(r.code, 1) << r.out;
      EXPECT_EQ(report.get("first_failure")->str(), "features");
    }
  }
  std::system(("rm -rf " + dir).c_str());
}

}  // namespace
