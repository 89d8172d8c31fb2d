// roadnn/testing.hpp (and roadnn_compare_with_reference underneath) as a user's unit
// test uses it: pass, fail with the worst element's coordinates in the message, the
// per-element rule, shape mismatches, unreadable references and misuse.
#include <gtest/gtest-spi.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include "roadnn/testing.hpp"
#include "weights/safetensors.h"

namespace {

class TestingHelpers : public testing::Test {
 protected:
  void SetUp() override {
    char tmpl[] = "/tmp/roadnn_testing_XXXXXX";
    ASSERT_NE(mkdtemp(tmpl), nullptr);
    dir_ = tmpl;
    ref_.resize(2 * 3 * 4);
    for (std::size_t i = 0; i < ref_.size(); ++i) ref_[i] = std::sin(0.7f * static_cast<float>(i)) * 2.0f;
    weights::Writer w;
    w.add_f32("features", {2, 3, 4}, ref_.data());
    const std::int64_t labels[2] = {1, 2};
    w.add_i64("labels", {2}, labels);
    w.write(path());
  }
  void TearDown() override { std::system(("rm -rf " + dir_).c_str()); }
  std::string path() const { return dir_ + "/ref.safetensors"; }

  std::string dir_;
  std::vector<float> ref_;
};

TEST_F(TestingHelpers, PassesWithinToleranceAndFailsNamingTheWorstElement) {
  std::vector<float> ours = ref_;
  ours[5] += 1e-5f;  // well inside 1e-4 * max|ref| (about 2e-4)
  auto r = roadnn::testing::compare(ours, {2, 3, 4}, path(), "features");
  EXPECT_TRUE(r.ok) << r.message;
  EXPECT_FALSE(r.error);
  EXPECT_EQ(r.count, 24);
  EXPECT_NEAR(r.max_abs_diff, 1e-5, 1e-6);
  EXPECT_EQ(r.worst, (std::vector<std::int64_t>{0, 1, 1}));  // flat 5 of [2, 3, 4]

  ours[1 * 12 + 2 * 4 + 3] += 0.5f;  // element [1, 2, 3]
  r = roadnn::testing::compare(ours, {2, 3, 4}, path(), "features");
  EXPECT_FALSE(r.ok);
  EXPECT_FALSE(r.error);
  EXPECT_EQ(r.worst, (std::vector<std::int64_t>{1, 2, 3}));
  EXPECT_EQ(r.failing, 1);
  EXPECT_NEAR(r.max_abs_diff, 0.5, 1e-6);
  EXPECT_NE(r.message.find("'features' [2, 3, 4]"), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("at [1, 2, 3]"), std::string::npos) << r.message;
  // What a GoogleTest user writes, and what the failure then says.
  EXPECT_NONFATAL_FAILURE(EXPECT_TRUE(r.ok) << r.message, "at [1, 2, 3]");
  // A looser tolerance accepts it.
  EXPECT_TRUE(roadnn::testing::compare(ours, {2, 3, 4}, path(), "features", roadnn::testing::rtol(0.3)).ok);
  EXPECT_TRUE(roadnn::testing::compare(ours, {2, 3, 4}, path(), "features", roadnn::testing::rtol(0, 0.5)).ok);
}

TEST_F(TestingHelpers, PerElementRuleScalesByEachReferenceValue) {
  std::vector<float> ours = ref_;
  ours[0] = 1e-3f;  // ref_[0] = sin(0) = 0: any absolute error fails per element
  EXPECT_TRUE(roadnn::testing::compare(ours, {2, 3, 4}, path(), "features", roadnn::testing::rtol(1e-3)).ok);
  auto r = roadnn::testing::compare(ours, {2, 3, 4}, path(), "features", roadnn::testing::rtol_per_element(1e-3));
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.worst, (std::vector<std::int64_t>{0, 0, 0}));
  EXPECT_NE(r.message.find("|ref|"), std::string::npos) << r.message;
}

TEST_F(TestingHelpers, NanInOursFails) {
  std::vector<float> ours = ref_;
  ours[7] = NAN;
  auto r = roadnn::testing::compare(ours, {2, 3, 4}, path(), "features");
  EXPECT_FALSE(r.ok);
  EXPECT_TRUE(std::isinf(r.max_abs_diff));
  EXPECT_EQ(r.worst, (std::vector<std::int64_t>{0, 1, 3}));
  EXPECT_NE(r.message.find("NaN/Inf A 1/0"), std::string::npos) << r.message;
}

TEST_F(TestingHelpers, ShapeMismatchIsAFailedComparisonNotAnError) {
  auto r = roadnn::testing::compare(ref_, {2, 12}, path(), "features");
  EXPECT_FALSE(r.ok);
  EXPECT_FALSE(r.error);
  EXPECT_NE(r.message.find("[2, 12]"), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("[2, 3, 4]"), std::string::npos) << r.message;
  r = roadnn::testing::compare(ref_, {2, 3, 5}, path(), "features");  // 30 elements for 24 values
  EXPECT_TRUE(r.error);
}

TEST_F(TestingHelpers, UnreadableReferencesAndWrongNamesAreErrorsNamingTheFile) {
  auto r = roadnn::testing::compare(ref_, {2, 3, 4}, dir_ + "/absent.safetensors", "features");
  EXPECT_FALSE(r.ok);
  EXPECT_TRUE(r.error);
  EXPECT_NE(r.message.find("i/o error"), std::string::npos) << r.message;
  EXPECT_NE(r.message.find(dir_ + "/absent.safetensors"), std::string::npos) << r.message;

  const char bad[] = "\x07\0\0\0\0\0\0\0{\"a\":1}";  // a tensor entry that is not an object
  std::ofstream(dir_ + "/bad.safetensors", std::ios::binary).write(bad, sizeof bad - 1);
  r = roadnn::testing::compare(ref_, {2, 3, 4}, dir_ + "/bad.safetensors", "features");
  EXPECT_TRUE(r.error);
  EXPECT_NE(r.message.find(dir_ + "/bad.safetensors"), std::string::npos) << r.message;

  r = roadnn::testing::compare(ref_, {2, 3, 4}, path(), "nope");
  EXPECT_TRUE(r.error);
  EXPECT_NE(r.message.find("no tensor 'nope'"), std::string::npos) << r.message;
  r = roadnn::testing::compare(ref_.data(), {2}, path(), "labels");
  EXPECT_TRUE(r.error);
  EXPECT_NE(r.message.find("I64"), std::string::npos) << r.message;
}

TEST_F(TestingHelpers, CApiRefusesMisuse) {
  roadnn_compare_result out;
  const std::int64_t shape[3] = {2, 3, 4};
  EXPECT_EQ(roadnn_compare_with_reference(ref_.data(), shape, 3, path().c_str(), "features", nullptr, nullptr),
            ROADNN_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(roadnn_compare_with_reference(nullptr, shape, 3, path().c_str(), "features", nullptr, &out),
            ROADNN_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(roadnn_last_error()).find("data is null"), std::string::npos);
  roadnn_tolerance bad = roadnn_tolerance_default();
  bad.rtol = -1;
  EXPECT_EQ(roadnn_compare_with_reference(ref_.data(), shape, 3, path().c_str(), "features", &bad, &out),
            ROADNN_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(roadnn_compare_with_reference(ref_.data(), shape, 3, path().c_str(), "features", nullptr, &out), ROADNN_OK);
  EXPECT_EQ(out.ok, 1);
  EXPECT_EQ(std::string(roadnn_last_error()), "");
  EXPECT_DOUBLE_EQ(roadnn_tolerance_default().rtol, 1e-4);
}

}  // namespace
