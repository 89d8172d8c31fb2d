// nncompare as users drive it: exit codes 0/1/2, one-line errors naming the file,
// the first failure in network order, tensors in one file only, NaN counts, JSON.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include "tests/nncompare/nncompare_run.h"
#include "weights/json.h"
#include "weights/safetensors.h"

namespace {

using nncompare_test::Result;

struct T {
  std::string name;
  std::vector<std::int64_t> shape;
  std::vector<float> values;
};

class NncompareCli : public testing::Test {
 protected:
  void SetUp() override {
    char tmpl[] = "/tmp/nncompare_test_XXXXXX";
    ASSERT_NE(mkdtemp(tmpl), nullptr);
    dir_ = tmpl;
  }
  void TearDown() override { std::system(("rm -rf " + dir_).c_str()); }

  std::string path(const std::string& f) const { return dir_ + "/" + f; }
  void write(const std::string& f, const std::vector<T>& tensors, const std::string& order = "") {
    weights::Writer w;
    for (const T& t : tensors) w.add_f32(t.name, t.shape, t.values.data());
    if (!order.empty()) w.set_metadata("dump.order", order);
    w.write(path(f));
  }
  Result run(const std::string& a, const std::string& b, const std::string& extra = "") {
    return nncompare_test::run(dir_, path(a) + " " + path(b) + " " + extra);
  }
  json::Value run_json(const std::string& a, const std::string& b, const std::string& extra, int expected_code) {
    Result r = run(a, b, "--json " + extra);
    EXPECT_EQ(r.code, expected_code) << r.out << r.err;
    return json::parse(r.out, "nncompare --json output");
  }
  static const json::Value& tensor(const json::Value& report, const std::string& name) {
    for (const json::Value& t : report.get("tensors")->array())
      if (t.get("name")->str() == name) return t;
    throw std::runtime_error("no tensor " + name + " in the report");
  }

  std::string dir_;
};

// Four tensors whose data order differs from the network order (dump.order).
std::vector<T> base() {
  return {{"late", {2, 3}, {1, 2, 3, 4, 5, 6}},
          {"early", {2, 2}, {1, -2, 3, -4}},
          {"middle", {3}, {10, 20, 30}},
          {"ints_like", {1}, {7}}};
}
const char* kOrder = "early,middle,late,ints_like";

TEST_F(NncompareCli, IdenticalFilesPassWithZeroDifferences) {
  write("a.st", base(), kOrder);
  write("b.st", base(), kOrder);
  Result r = run("a.st", "b.st");
  EXPECT_EQ(r.code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("4 compared, 0 failed"), std::string::npos) << r.out;
  EXPECT_EQ(r.err, "");
}

TEST_F(NncompareCli, FirstFailureFollowsTheReferencesDumpOrderNotTheDataOrder) {
  auto a = base();
  a[0].values[5] += 1.0f;  // "late": last in network order but first in the file
  a[2].values[1] += 1.0f;  // "middle" at [1]
  write("a.st", a);  // A has no dump.order: the reference's decides
  write("b.st", base(), kOrder);
  Result r = run("a.st", "b.st");
  EXPECT_EQ(r.code, 1) << r.out << r.err;
  EXPECT_NE(r.out.find("first failure in network order: middle: max|diff| 1 "), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("at [1] (21 vs 20)"), std::string::npos) << r.out;
  EXPECT_LT(r.out.find("  early "), r.out.find("  middle "));
  EXPECT_LT(r.out.find("  middle "), r.out.find("  late "));
  r = run("a.st", "b.st", "--brief");  // the passing tensors are left out
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(r.out.find("  early "), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("FAIL  middle "), std::string::npos) << r.out;

  // Without dump.order anywhere: the reference's data order, where "late" comes first.
  write("b2.st", base());
  json::Value j = run_json("a.st", "b2.st", "", 1);
  EXPECT_EQ(j.get("first_failure")->str(), "late");
  EXPECT_EQ(tensor(j, "late").get("worst_index")->array()[1].number(), 2);  // [1, 2] of shape [2, 3]
}

TEST_F(NncompareCli, ToleranceRuleIsScaledByMaxRefOrPerElement) {
  auto a = base();
  a[2].values[0] = 10.5f;  // |diff| 0.5; max|ref| of "middle" is 30
  write("a.st", a, kOrder);
  write("b.st", base(), kOrder);
  EXPECT_EQ(run("a.st", "b.st", "--rtol 0.02").code, 0);    // 0.5 <= 0.02 * 30
  EXPECT_EQ(run("a.st", "b.st", "--rtol 0.01").code, 1);    // 0.5 > 0.3
  EXPECT_EQ(run("a.st", "b.st", "--rtol 0 --atol 0.5").code, 0);
  EXPECT_EQ(run("a.st", "b.st", "--rtol 0.02 --per-element").code, 1);  // 0.5 > 0.02 * 10
  EXPECT_EQ(run("a.st", "b.st", "--rtol 0.05 --per-element").code, 0);
  json::Value j = run_json("a.st", "b.st", "--rtol 0.01", 1);
  const json::Value& m = tensor(j, "middle");
  EXPECT_DOUBLE_EQ(m.get("max_abs_diff")->number(), 0.5);
  EXPECT_DOUBLE_EQ(m.get("max_abs_ref")->number(), 30.0);
  EXPECT_NEAR(m.get("max_rel_diff")->number(), 0.5 / 30, 1e-9);
  EXPECT_NEAR(m.get("mean_abs_diff")->number(), 0.5 / 3, 1e-9);
  EXPECT_NEAR(m.get("allowed")->number(), 0.3, 1e-9);
  EXPECT_EQ(m.get("failing_elements")->number(), 1);
}

TEST_F(NncompareCli, ShapeMismatchFailsAndIsNamed) {
  auto a = base();
  a[1].shape = {4};
  write("a.st", a, kOrder);
  write("b.st", base(), kOrder);
  Result r = run("a.st", "b.st");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.out.find("shape mismatch: [4] vs reference [2, 2]"), std::string::npos) << r.out;
  json::Value j = run_json("a.st", "b.st", "", 1);
  EXPECT_EQ(j.get("first_failure")->str(), "early");
  EXPECT_EQ(tensor(j, "early").get("status")->str(), "shape_mismatch");
}

TEST_F(NncompareCli, DTypeMismatchFails) {
  write("b.st", {{"x", {2}, {1, 2}}});
  weights::Writer w;
  const std::int64_t v[2] = {1, 2};
  w.add_i64("x", {2}, v);
  w.write(path("a.st"));
  json::Value j = run_json("a.st", "b.st", "", 1);
  EXPECT_EQ(tensor(j, "x").get("status")->str(), "dtype_mismatch");
}

TEST_F(NncompareCli, NanOnOneSideFailsAndIsCounted) {
  auto a = base();
  a[1].values[2] = NAN;
  auto b = base();
  b[2].values[0] = NAN;  // NaN in both at the same place below: equal
  auto a2 = a;
  a2[2].values[0] = NAN;
  write("a.st", a2, kOrder);
  write("b.st", b, kOrder);
  json::Value j = run_json("a.st", "b.st", "", 1);
  const json::Value& e = tensor(j, "early");
  EXPECT_EQ(e.get("nan")->number(), 1);
  EXPECT_EQ(e.get("ref_nan")->number(), 0);
  EXPECT_TRUE(e.get("max_abs_diff")->is_null());  // +inf has no JSON spelling
  EXPECT_EQ(e.get("worst_index")->array()[0].number(), 1);
  EXPECT_EQ(e.get("worst_index")->array()[1].number(), 0);
  const json::Value& m = tensor(j, "middle");
  EXPECT_EQ(m.get("status")->str(), "ok");
  EXPECT_EQ(m.get("nan")->number(), 1);
  EXPECT_EQ(m.get("ref_nan")->number(), 1);
  Result r = run("a.st", "b.st");
  EXPECT_NE(r.out.find("NaN/Inf A 1/0, ref 0/0"), std::string::npos) << r.out;
}

TEST_F(NncompareCli, TensorsInOneFileOnlyAreListedButDoNotFail) {
  auto a = base();
  a.push_back({"extra_a", {1}, {1}});
  auto b = base();
  b.erase(b.begin() + 3);  // "ints_like" only in A
  b.push_back({"extra_b", {1}, {1}});
  write("a.st", a);
  write("b.st", b);
  Result r = run("a.st", "b.st");
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("only in A"), std::string::npos);
  EXPECT_NE(r.out.find("only in the reference"), std::string::npos);
  json::Value j = run_json("a.st", "b.st", "", 0);
  EXPECT_EQ(j.get("only_in_a")->number(), 2);
  EXPECT_EQ(j.get("only_in_reference")->number(), 1);
  EXPECT_EQ(tensor(j, "extra_b").get("status")->str(), "only_in_ref");
  EXPECT_TRUE(j.get("ok")->boolean());
  EXPECT_TRUE(j.get("first_failure")->is_null());
}

TEST_F(NncompareCli, FilterSelectsTensors) {
  auto a = base();
  a[0].values[0] = 100;  // "late" fails
  write("a.st", a, kOrder);
  write("b.st", base(), kOrder);
  EXPECT_EQ(run("a.st", "b.st", "--filter '^(early|mid)'").code, 0);
  json::Value j = run_json("a.st", "b.st", "--filter 'at'", 1);
  EXPECT_EQ(j.get("tensors")->array().size(), 1u);  // "late" only
}

TEST_F(NncompareCli, MissingAndMalformedFilesAreUsageErrorsNamingTheFile) {
  write("b.st", base());
  Result r = run("absent.st", "b.st");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find(path("absent.st")), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_EQ(r.out, "");

  std::vector<std::uint8_t> bytes = weights::Writer().bytes();
  std::ofstream(path("short.st"), std::ios::binary).write("\x10\x00\x00", 3);
  r = run("b.st", "short.st");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find(path("short.st")), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;

  // A header promising more data than there is.
  std::string header = "{\"x\":{\"dtype\":\"F32\",\"shape\":[4],\"data_offsets\":[0,16]}}";
  std::uint64_t n = header.size();
  std::ofstream f(path("trunc.st"), std::ios::binary);
  f.write(reinterpret_cast<const char*>(&n), 8);
  f << header << "abcd";
  f.close();
  r = run("trunc.st", "b.st");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find(path("trunc.st")), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("truncated"), std::string::npos) << r.err;
}

TEST_F(NncompareCli, UsageErrorsExitTwo) {
  write("a.st", base());
  EXPECT_EQ(nncompare_test::run(dir_, path("a.st")).code, 2);
  EXPECT_EQ(run("a.st", "a.st", "--rtol -1").code, 2);
  Result r = run("a.st", "a.st", "--filter '('");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--filter"), std::string::npos) << r.err;
  r = nncompare_test::run(dir_, "--help");
  EXPECT_EQ(r.code, 0);
  EXPECT_NE(r.out.find("--rtol"), std::string::npos);
  EXPECT_NE(r.out.find("exit status"), std::string::npos);
}

}  // namespace
