#include <gtest/gtest.h>

#include <cmath>

#include "stixel/anchors.h"
#include "stixel/error.h"
#include "stixel/predictor.h"
#include "tests/error_of.h"

namespace {

// The reference table (6 decimals) of tangent anchors (4, 66, 64), a = pi/2.72.
const double kTangentTable[64] = {
    4.000000,  4.501942,  5.004223,  5.507179,  6.011151,  6.516484,  7.023522,  7.532618,
    8.044129,  8.558419,  9.075859,  9.596828,  10.121718, 10.650931, 11.184879, 11.723991,
    12.268709, 12.819495, 13.376827, 13.941203, 14.513145, 15.093199, 15.681937, 16.279960,
    16.887902, 17.506430, 18.136252, 18.778114, 19.432808, 20.101179, 20.784122, 21.482595,
    22.197618, 22.930286, 23.681772, 24.453335, 25.246330, 26.062221, 26.902585, 27.769132,
    28.663715, 29.588351, 30.545232, 31.536754, 32.565538, 33.634455, 34.746663, 35.905642,
    37.115237, 38.379704, 39.703777, 41.092726, 42.552447, 44.089549, 45.711473, 47.426625,
    49.244539, 51.176074, 53.233652, 55.431556, 57.786285, 60.317010, 63.046132, 66.000000};

}  // namespace

TEST(Anchors, TangentMatchesTheReferenceTable) {
  const stixel::Anchors a = stixel::tangent_anchors();
  ASSERT_EQ(a.size(), 64);
  // Table rounding (5e-7) plus float rounding (half an ulp, < 4e-6 below 66).
  for (int i = 0; i < 64; ++i) EXPECT_NEAR(a.depth[i], kTangentTable[i], 5e-7 + 4e-6) << i;
  EXPECT_EQ(a.depth[0], 4.0f);
  EXPECT_EQ(a.depth[63], 66.0f);
  // Strictly increasing, spacing 0.502 m at 4 m to 2.954 m at 66 m.
  for (int i = 1; i < 64; ++i) EXPECT_GT(a.depth[i], a.depth[i - 1]);
  EXPECT_NEAR(a.depth[1] - a.depth[0], 0.502, 1e-3);
  EXPECT_NEAR(a.depth[63] - a.depth[62], 2.954, 1e-3);
}

TEST(Anchors, LinearIsLinspace) {
  const stixel::Anchors a = stixel::linear_anchors(5, 69, 64);
  ASSERT_EQ(a.size(), 64);
  EXPECT_EQ(a.depth[0], 5.0f);
  EXPECT_EQ(a.depth[63], 69.0f);
  for (int i = 0; i < 64; ++i) EXPECT_EQ(a.depth[i], static_cast<float>(5.0 + i * (64.0 / 63.0)));
  EXPECT_NEAR(a.depth[1] - a.depth[0], 1.01587, 1e-5);
}

TEST(Anchors, SpecRoundTrip) {
  EXPECT_EQ(stixel::anchor_spec(stixel::tangent_anchors()), "tangent:4,66,64");
  EXPECT_EQ(stixel::anchor_spec(stixel::linear_anchors(5, 69, 64)), "linear:5,69,64");
  EXPECT_EQ(stixel::anchor_spec(stixel::linear_anchors(4.5, 70.25, 32)), "linear:4.5,70.25,32");
  for (const char* spec : {"tangent", "tangent:4,66,64", "linear:5,69,64", "linear:0.5,80,128"}) {
    const stixel::Anchors a = stixel::parse_anchor_spec(spec, "test");
    const stixel::Anchors b = stixel::parse_anchor_spec(stixel::anchor_spec(a), "test");
    EXPECT_EQ(a.depth, b.depth) << spec;
  }
  EXPECT_EQ(stixel::parse_anchor_spec("tangent", "t").depth, stixel::tangent_anchors().depth);
}

TEST(Anchors, BadSpecsAreErrors) {
  for (const char* spec : {"", "log:1,2,3", "linear", "linear:5,69", "linear:5,69,64,1",
                           "linear:5;69;64", "tangent:66,4,64", "tangent:4,66,1", "linear:0,10,64",
                           "linear:5,69,6.5", "tangent:4,66,x", "linear:nan,5,3",
                           // issue 12, row 10: beyond float32, or too narrow for it
                           "tangent:1e-300,1e300,64", "linear:1e-300,1,64", "tangent:1,1e39,64",
                           "linear:1,1.0000001,64"}) {
    try {
      stixel::parse_anchor_spec(spec, "weights.safetensors");
      ADD_FAILURE() << "no error for '" << spec << "'";
    } catch (const stixel::Error& e) {
      EXPECT_EQ(std::string(e.what()).rfind("weights.safetensors: ", 0), 0u) << e.what();
    }
  }
  // From a model's metadata the error names the file and the key.
  const std::string m = testutil::error_of([] {
    stixel::settings_from_metadata({{"stixelnext.anchors", "tangent:1e-300,1e300,64"}}, "w.safetensors");
  });
  EXPECT_EQ(m.rfind("w.safetensors: metadata stixelnext.anchors: tangent anchors: start and end must lie in the float range", 0),
            0u) << m;
}

// Issue 12, finding 5: an anchor spec or a metadata value from a model file is quoted
// escaped and cut in the error.
TEST(HostileMessages, AnchorSpecAndMetadataStayOnePrintableLine) {
  const std::string h = testutil::hostile_text();
  for (const std::string& spec : {h, "tangent:" + h, "linear:1,2," + h}) {
    const std::string m = testutil::error_of([&] { stixel::parse_anchor_spec(spec, "w.safetensors"); });
    EXPECT_TRUE(testutil::is_one_printable_line(m, 400)) << m.size() << ": " << m.substr(0, 200);
  }
  for (const char* key : {"stixelnext.input_height", "stixelnext.normalization", "stixelnext.head",
                          "stixelnext.anchors"}) {
    const std::map<std::string, std::string> md{{key, h}};
    const std::string m = testutil::error_of([&] { stixel::settings_from_metadata(md, "w.safetensors"); });
    EXPECT_NE(m.find("w.safetensors"), std::string::npos) << key;
    EXPECT_TRUE(testutil::is_one_printable_line(m, 400)) << key << ": " << m.substr(0, 200);
  }
}

// Found by tests/fuzz/fuzz_anchors: a bad count quoted the whole spec raw, so control
// bytes in it (minimized: "tangent:5,5,\r...\r344444") broke the one-line message.
TEST(Anchors, BadCountMessageEscapesTheSpec) {
  std::string m = testutil::error_of(
      [] { stixel::parse_anchor_spec("tangent:5,5,\r\r\r344444", "--anchors"); });
  EXPECT_NE(m.find("anchor count must be an integer"), std::string::npos) << m;
  EXPECT_TRUE(testutil::is_one_printable_line(m)) << m;
}
