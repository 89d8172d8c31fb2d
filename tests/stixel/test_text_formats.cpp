#include <gtest/gtest.h>

#include <cmath>

#include "stixel/error.h"
#include "stixel/text_formats.h"

namespace {

stixel::StixelWorld small_world() {
  stixel::StixelWorld w;
  stixel::Stixel a;
  a.u = 760;
  a.vT = 640;
  a.vB = 664;
  a.d = 70.47f;
  a.label = 1;
  a.width = 8;
  a.confidence = 0.36f;
  a.cluster = -1;
  stixel::Stixel b;
  b.u = 8;
  b.vT = 1;
  b.vB = 1281;
  b.d = 4.5019417f;
  b.width = 8;
  b.confidence = 1.0f;
  b.idx = 2;
  w.stixels = {a, b};
  w.context.name = "frame_1";
  return w;
}

}  // namespace

TEST(TextFormats, CsvUsesTheReaderLayout) {
  const stixel::StixelWorld w = small_world();
  EXPECT_EQ(stixel::to_csv(w),
            "img,u,vT,vB,d,label,p\n"
            "frame_1,760,640,664,70.47,1,0.36\n"
            "frame_1,8,1,1281,4.5019417,0,1\n");
  stixel::CsvOptions o;
  o.img = "validation/a,\"b\".png";
  o.extended = true;
  EXPECT_EQ(stixel::to_csv(w, o),
            "img,u,vT,vB,d,label,p,width,cluster,idx\n"
            "\"validation/a,\"\"b\"\".png\",760,640,664,70.47,1,0.36,8,-1,0\n"
            "\"validation/a,\"\"b\"\".png\",8,1,1281,4.5019417,0,1,8,0,2\n");
  // Floats read back exactly.
  EXPECT_EQ(std::stof("4.5019417"), 4.5019417f);
}

TEST(TextFormats, JsonIsTheProto3Mapping) {
  stixel::StixelWorld w = small_world();
  w.stixels[1].d = NAN;
  w.context.calibration.img_name = "a\"b\n";
  w.context.calibration.K = {1.5f, 0, -INFINITY};
  w.context.calibration.distortion_model = 1;
  w.image = {1, 2, 3, 4};
  stixel::JsonOptions o;
  o.pretty = false;
  EXPECT_EQ(stixel::to_json(w, o),
            "{\"stixel\": [{\"u\": 760, \"vT\": 640, \"vB\": 664, \"d\": 70.47, \"label\": 1, \"width\": 8, "
            "\"confidence\": 0.36, \"cluster\": -1},{\"u\": 8, \"vT\": 1, \"vB\": 1281, \"d\": \"NaN\", "
            "\"width\": 8, \"confidence\": 1, \"idx\": 2}],\"context\": {\"name\": \"frame_1\", \"calibration\": "
            "{\"K\": [1.5, 0, \"-Infinity\"], \"DistortionModel\": 1, \"imgName\": \"a\\\"b\\n\"}}}");
  o.include_image = true;
  const std::string with_image = stixel::to_json(w, o);
  EXPECT_NE(with_image.find("\"image\": \"AQIDBA==\""), std::string::npos) << with_image;
  EXPECT_EQ(stixel::to_json(stixel::StixelWorld{}, o), "{}");
  // -0.0 is not the default and must keep its sign ("-0" would parse as 0).
  stixel::StixelWorld z;
  z.stixels.emplace_back();
  z.stixels[0].confidence = -0.0f;
  EXPECT_EQ(stixel::to_json(z, o), "{\"stixel\": [{\"confidence\": -0.0}]}");
  w.context.name = "\xff";
  EXPECT_THROW(stixel::to_json(w, o), stixel::Error);
}

TEST(TextFormats, PrettyJsonHasOneStixelPerLine) {
  const std::string j = stixel::to_json(small_world());
  EXPECT_EQ(j.rfind("{\n  \"stixel\": [\n    {\"u\": 760", 0), 0u) << j;
  EXPECT_NE(j.find("},\n    {\"u\": 8"), std::string::npos) << j;
  EXPECT_NE(j.find("\n  ],\n  \"context\": {\"name\": \"frame_1\"}"), std::string::npos) << j;
  EXPECT_EQ(j.substr(j.size() - 4), "}\n}\n");
}
