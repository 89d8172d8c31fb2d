// .stx1 wire format: exact bytes, round trips, protobuf's leniencies and
// malformed input.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

#include "stixel/error.h"
#include "stixel/stx1.h"

using Bytes = std::vector<std::uint8_t>;

namespace {

Bytes float_le(float f) {
  std::uint32_t b;
  std::memcpy(&b, &f, 4);
  return {static_cast<std::uint8_t>(b), static_cast<std::uint8_t>(b >> 8), static_cast<std::uint8_t>(b >> 16),
          static_cast<std::uint8_t>(b >> 24)};
}

Bytes cat(std::initializer_list<Bytes> parts) {
  Bytes out;
  for (const Bytes& p : parts) out.insert(out.end(), p.begin(), p.end());
  return out;
}

stixel::StixelWorld decode(const Bytes& b) { return stixel::decode_stx1(b.data(), b.size(), "t.stx1"); }

std::string decode_error(const Bytes& b) {
  try {
    decode(b);
  } catch (const stixel::Error& e) {
    return e.what();
  }
  return "";
}

stixel::StixelWorld full_world() {
  stixel::StixelWorld w;
  stixel::Stixel s;
  s.u = 864;
  s.vT = 754;
  s.vB = 845;
  s.d = 23.681772f;
  s.label = 7;
  s.width = 8;
  s.confidence = 0.75f;
  s.idx = 3;
  s.cluster = -1;
  w.stixels.push_back(s);
  stixel::Stixel z;  // all defaults: an empty sub-message
  w.stixels.push_back(z);
  w.image = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A, 1, 2, 3};
  w.context.name = "frame_0001";
  auto& c = w.context.calibration;
  c.K = {2056.28f, 0, 939.578f, 0, 2056.28f, 641.103f, 0, 0, 1};
  c.T = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  c.R = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  c.D = {0.0449f, -0.354f, 0, 0, 0};
  c.distortion_model = stixel::kModelPlumbBob;
  c.reference = "Vehicle2Camera";
  c.img_name = "frame_0001.png";
  c.width = 1920;
  c.height = 1280;
  c.channels = 3;
  w.context.clusters = 4;
  return w;
}

void expect_equal(const stixel::StixelWorld& a, const stixel::StixelWorld& b) {
  ASSERT_EQ(a.stixels.size(), b.stixels.size());
  for (std::size_t i = 0; i < a.stixels.size(); ++i) {
    const auto &x = a.stixels[i], &y = b.stixels[i];
    EXPECT_EQ(x.u, y.u);
    EXPECT_EQ(x.vT, y.vT);
    EXPECT_EQ(x.vB, y.vB);
    EXPECT_EQ(std::memcmp(&x.d, &y.d, 4), 0);
    EXPECT_EQ(x.label, y.label);
    EXPECT_EQ(x.width, y.width);
    EXPECT_EQ(std::memcmp(&x.confidence, &y.confidence, 4), 0);
    EXPECT_EQ(x.idx, y.idx);
    EXPECT_EQ(x.cluster, y.cluster);
  }
  EXPECT_EQ(a.image, b.image);
  EXPECT_EQ(a.context.name, b.context.name);
  EXPECT_EQ(a.context.clusters, b.context.clusters);
  const auto &p = a.context.calibration, &q = b.context.calibration;
  EXPECT_EQ(p.K, q.K);
  EXPECT_EQ(p.T, q.T);
  EXPECT_EQ(p.R, q.R);
  EXPECT_EQ(p.D, q.D);
  EXPECT_EQ(p.distortion_model, q.distortion_model);
  EXPECT_EQ(p.reference, q.reference);
  EXPECT_EQ(p.img_name, q.img_name);
  EXPECT_EQ(p.width, q.width);
  EXPECT_EQ(p.height, q.height);
  EXPECT_EQ(p.channels, q.channels);
}

}  // namespace

TEST(Stx1, StixelBytesMatchTheWorkedExample) {
  stixel::StixelWorld w;
  stixel::Stixel s;
  s.u = 864;
  s.vT = 754;
  s.vB = 845;
  s.d = 23.681772f;
  s.width = 8;
  s.confidence = 0.5f;
  w.stixels.push_back(s);
  const Bytes expect = cat({{0x0a, 0x15, 0x08, 0xe0, 0x06, 0x10, 0xf2, 0x05, 0x18, 0xcd, 0x06, 0x25},
                            float_le(23.681772f), {0x30, 0x08, 0x3d}, float_le(0.5f)});
  EXPECT_EQ(stixel::encode_stx1(w), expect);
}

TEST(Stx1, DefaultsOmittedNegativesTenBytesMinusZeroKept) {
  stixel::StixelWorld w;
  EXPECT_TRUE(stixel::encode_stx1(w).empty());
  w.stixels.emplace_back();
  EXPECT_EQ(stixel::encode_stx1(w), (Bytes{0x0a, 0x00}));
  w.stixels[0].cluster = -1;
  EXPECT_EQ(stixel::encode_stx1(w),
            (Bytes{0x0a, 0x0b, 0x48, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0x01}));
  w.stixels[0].cluster = 0;
  w.stixels[0].confidence = -0.0f;  // proto3 omits only +0.0
  EXPECT_EQ(stixel::encode_stx1(w), (Bytes{0x0a, 0x05, 0x3d, 0x00, 0x00, 0x00, 0x80}));
  // Context with only clusters = -1; a present-but-empty calibration.
  stixel::StixelWorld c;
  c.context.clusters = -1;
  EXPECT_EQ(stixel::encode_stx1(c),
            (Bytes{0x1a, 0x0b, 0x18, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0x01}));
  stixel::StixelWorld e;
  e.has_context = true;
  EXPECT_EQ(stixel::encode_stx1(e), (Bytes{0x1a, 0x00}));
  e.context.has_calibration = true;
  EXPECT_EQ(stixel::encode_stx1(e), (Bytes{0x1a, 0x02, 0x12, 0x00}));
}

TEST(Stx1, CalibrationIsPackedInFieldOrder) {
  stixel::StixelWorld w;
  w.context.name = "n";
  w.context.calibration.K = {1.0f, 2.0f};
  w.context.calibration.width = 1920;
  w.context.calibration.reference = "R";
  const Bytes expect = cat({{0x1a, 0x15, 0x0a, 0x01, 'n', 0x12, 0x10, 0x0a, 0x08}, float_le(1.0f), float_le(2.0f),
                            {0x32, 0x01, 'R', 0x40, 0x80, 0x0f}});
  EXPECT_EQ(stixel::encode_stx1(w), expect);
}

TEST(Stx1, RoundTripKeepsEveryField) {
  const stixel::StixelWorld w = full_world();
  const Bytes b = stixel::encode_stx1(w);
  const stixel::StixelWorld r = decode(b);
  expect_equal(w, r);
  EXPECT_TRUE(r.has_context);
  EXPECT_TRUE(r.context.has_calibration);
  EXPECT_EQ(stixel::encode_stx1(r), b);
  // NaN and infinities survive bit for bit.
  stixel::StixelWorld n;
  n.stixels.resize(2);
  n.stixels[0].d = NAN;
  n.stixels[1].confidence = -INFINITY;
  const stixel::StixelWorld m = decode(stixel::encode_stx1(n));
  EXPECT_TRUE(std::isnan(m.stixels[0].d));
  EXPECT_EQ(m.stixels[1].confidence, -INFINITY);
}

TEST(Stx1, ReaderAcceptsWhatProtobufAccepts) {
  // Fields out of order, a repeated scalar (last wins), unknown fields of every
  // wire type incl. a nested group, unpacked K values, two packed K records
  // (concatenated), and the context given twice (merged).
  const Bytes stixel = cat({{0x0a, 0x1b},
                            {0x30, 0x08},                    // width 8
                            {0x08, 0x05},                    // u 5
                            {0x08, 0x07},                    // u 7 (wins)
                            {0x50, 0x96, 0x01},              // field 10 varint (unknown)
                            {0x59, 1, 2, 3, 4, 5, 6, 7, 8},  // field 11 fixed64
                            {0x65, 1, 2, 3, 4},              // field 12 fixed32
                            {0x6b, 0x08, 0x01, 0x6c}});      // field 13 group {field 1 varint}
  const Bytes ctx1 = cat({{0x1a, 0x0e, 0x12, 0x0c, 0x0d}, float_le(1.0f), {0x0d}, float_le(2.0f), {0x48, 0x05}});
  const Bytes ctx2 = cat({{0x1a, 0x0b, 0x0a, 0x01, 'x', 0x12, 0x06, 0x0a, 0x04}, float_le(3.0f)});
  const Bytes unknown_top = {0x22, 0x03, 'a', 'b', 'c'};  // field 4, length-delimited
  const stixel::StixelWorld w = decode(cat({ctx1, stixel, unknown_top, ctx2}));
  ASSERT_EQ(w.stixels.size(), 1u);
  EXPECT_EQ(w.stixels[0].u, 7);
  EXPECT_EQ(w.stixels[0].width, 8);
  EXPECT_EQ(w.context.name, "x");
  EXPECT_EQ(w.context.calibration.K, (std::vector<float>{1.0f, 2.0f, 3.0f}));
  EXPECT_EQ(w.context.calibration.height, 5);
  // int32 from a varint wider than 32 bits keeps the low 32 bits.
  const stixel::StixelWorld big = decode({0x0a, 0x06, 0x08, 0x80, 0x80, 0x80, 0x80, 0x10});
  EXPECT_EQ(big.stixels[0].u, 0);
}

TEST(Stx1, CorruptFilesGiveClearErrors) {
  const Bytes good = stixel::encode_stx1(full_world());
  struct Case {
    Bytes bytes;
    std::string needle;
  };
  const std::vector<Case> cases = {
      {{0x0a}, "truncated varint in StixelWorld.stixel"},
      {{0x0a, 0x05, 0x08}, "length 5 of StixelWorld.stixel runs past the end (1 bytes left)"},
      {{0x0a, 0x02, 0x08, 0x96}, "truncated varint in Stixel.u"},
      {{0x0a, 0x03, 0x25, 0x00, 0x00}, "truncated fixed32 in Stixel.d"},
      {{0x0a, 0x0c, 0x08, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0x01},
       "malformed varint (more than 10 bytes) in Stixel.u"},
      {{0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0x01}, "malformed varint"},
      {{0x0a, 0x05, 0x0d, 0x00, 0x00, 0x80, 0x3f}, "field Stixel.u has wire type 5 (fixed32), expected 0 (varint)"},
      {{0x0a, 0x02, 0x20, 0x01}, "field Stixel.d has wire type 0 (varint), expected 5 (fixed32)"},
      {{0x08, 0x01}, "field StixelWorld.stixel has wire type 0"},
      {{0x1e, 0x00}, "invalid wire type 6"},
      {{0x0f}, "invalid wire type 7"},
      {{0x02, 0x00}, "invalid field number 0"},
      {{0x0c}, "unexpected end-group"},
      {{0x2b, 0x08, 0x01}, "truncated varint in StixelWorld"},  // group never closed
      {{0x2b, 0x14}, "mismatched end-group"},
      {{0x1a, 0x03, 0x0a, 0x01, 0xff}, "field Context.name is not valid UTF-8"},
      {{0x1a, 0x05, 0x12, 0x03, 0x0a, 0x01, 0x00}, "packed CameraInfo.K has 1 bytes, not a multiple of 4"},
      {{0x1a, 0x04, 0x12, 0x02, 0x0a, 0x05}, "length 5 of CameraInfo.K runs past the end"},
      {{0x12, 0x80, 0x80, 0x80, 0x80, 0x08}, "length 2147483648 of StixelWorld.image runs past the end"},
  };
  for (const Case& c : cases) {
    const std::string msg = decode_error(c.bytes);
    EXPECT_EQ(msg.rfind("t.stx1: byte ", 0), 0u) << "expected '" << c.needle << "', got '" << msg << "'";
    EXPECT_NE(msg.find(c.needle), std::string::npos) << "expected '" << c.needle << "', got '" << msg << "'";
  }
  // Cut inside a field or sub-message: an error. (A cut exactly between two
  // top-level fields leaves a valid, shorter message, as with protobuf.)
  // full_world() has three such boundaries: after each stixel and the image.
  int valid_prefixes = 0;
  for (std::size_t n = 1; n < good.size(); ++n) {
    const Bytes cut(good.begin(), good.begin() + n);
    try {
      decode(cut);
      ++valid_prefixes;
    } catch (const stixel::Error& e) {
      EXPECT_EQ(std::string(e.what()).rfind("t.stx1: byte ", 0), 0u);
    }
  }
  EXPECT_EQ(valid_prefixes, 3);
}

TEST(Stx1, RandomDamageNeverCrashes) {
  const Bytes good = stixel::encode_stx1(full_world());
  std::mt19937 rng(5);
  int errors = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    Bytes b = good;
    const int edits = 1 + trial % 4;
    for (int k = 0; k < edits; ++k) b[rng() % b.size()] = static_cast<std::uint8_t>(rng());
    if (trial % 3 == 0) b.resize(rng() % b.size());
    try {
      decode(b);
    } catch (const stixel::Error&) {
      ++errors;
    }
  }
  EXPECT_GT(errors, 1000);
}

TEST(Stx1, WriterRejectsInvalidUtf8) {
  stixel::StixelWorld w;
  w.context.name = "bad\xff";
  EXPECT_THROW(stixel::encode_stx1(w), stixel::Error);
  w.context.name = "ok";
  w.context.calibration.img_name = "\xc0\xaf";  // overlong '/'
  EXPECT_THROW(stixel::encode_stx1(w), stixel::Error);
  w.context.calibration.img_name = "\xed\xa0\x80";  // surrogate
  EXPECT_THROW(stixel::encode_stx1(w), stixel::Error);
  w.context.calibration.img_name = "Stra\xc3\x9f" "e \xf0\x9f\x9a\x97";
  EXPECT_NO_THROW(stixel::encode_stx1(w));
}

TEST(Stx1, ReadFileErrorsNameThePath) {
  try {
    stixel::read_stx1("/nonexistent/x.stx1");
    ADD_FAILURE();
  } catch (const stixel::Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("/nonexistent/x.stx1: cannot open", 0), 0u) << e.what();
  }
  EXPECT_THROW(stixel::read_stx1("/"), stixel::Error);
}
