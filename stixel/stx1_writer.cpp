// proto3 wire-format writer for StixelWorld (field numbers in stx1.h's schema,
// docs/STIXEL_FORMATS.md).
#include <cstring>

#include "stixel/error.h"
#include "stixel/stx1.h"

namespace stixel {
namespace {

enum WireType { kVarint = 0, kLen = 2, kFixed32 = 5 };

std::size_t varint_size(std::uint64_t v) {
  std::size_t n = 1;
  while (v >= 0x80) {
    v >>= 7;
    ++n;
  }
  return n;
}

// int32 values are encoded as their sign-extended 64-bit two's complement, so
// negative values take 10 bytes (proto3 int32 / enum rule).
std::uint64_t int32_wire(std::int32_t v) {
  return static_cast<std::uint64_t>(static_cast<std::int64_t>(v));
}

std::uint32_t float_bits(float f) {
  std::uint32_t b;
  std::memcpy(&b, &f, 4);
  return b;
}

// Sizes of single fields with field number <= 15 (one tag byte), 0 if omitted.
std::size_t int32_field_size(std::int32_t v) { return v ? 1 + varint_size(int32_wire(v)) : 0; }
std::size_t float_field_size(float f) { return float_bits(f) ? 5 : 0; }
std::size_t len_field_size(std::size_t len) { return 1 + varint_size(len) + len; }

class Out {
 public:
  explicit Out(std::vector<std::uint8_t>& b) : b_(b) {}
  void varint(std::uint64_t v) {
    while (v >= 0x80) {
      b_.push_back(static_cast<std::uint8_t>(v | 0x80));
      v >>= 7;
    }
    b_.push_back(static_cast<std::uint8_t>(v));
  }
  void tag(int field, WireType wt) { varint(static_cast<std::uint64_t>(field) << 3 | wt); }
  void int32_field(int field, std::int32_t v) {
    if (!v) return;
    tag(field, kVarint);
    varint(int32_wire(v));
  }
  void float_field(int field, float f) {
    const std::uint32_t bits = float_bits(f);
    if (!bits) return;  // +0.0 is the default; -0.0 is not
    tag(field, kFixed32);
    fixed32(bits);
  }
  void fixed32(std::uint32_t bits) {
    for (int k = 0; k < 4; ++k) b_.push_back(static_cast<std::uint8_t>(bits >> (8 * k)));
  }
  void bytes_field(int field, const void* data, std::size_t n) {
    if (!n) return;
    tag(field, kLen);
    varint(n);
    const auto* p = static_cast<const std::uint8_t*>(data);
    b_.insert(b_.end(), p, p + n);
  }
  void packed_floats(int field, const std::vector<float>& v) {
    if (v.empty()) return;
    tag(field, kLen);
    varint(4 * v.size());
    for (float f : v) fixed32(float_bits(f));
  }
  void message_field(int field, const std::vector<std::uint8_t>& body) {
    tag(field, kLen);
    varint(body.size());
    b_.insert(b_.end(), body.begin(), body.end());
  }

 private:
  std::vector<std::uint8_t>& b_;
};

void check_utf8(const std::string& s, const char* field) {
  if (!is_valid_utf8(s))
    throw Error(std::string("stx1: ") + field + " is not valid UTF-8 (protobuf strings must be)");
}

bool calibration_is_default(const CameraInfo& c) {
  return c.K.empty() && c.T.empty() && c.R.empty() && c.D.empty() && c.distortion_model == 0 &&
         c.reference.empty() && c.img_name.empty() && c.width == 0 && c.height == 0 &&
         c.channels == 0;
}

std::vector<std::uint8_t> encode_calibration(const CameraInfo& c) {
  check_utf8(c.reference, "context.calibration.reference");
  check_utf8(c.img_name, "context.calibration.img_name");
  std::vector<std::uint8_t> b;
  Out o(b);
  o.packed_floats(1, c.K);
  o.packed_floats(2, c.T);
  o.packed_floats(3, c.R);
  o.packed_floats(4, c.D);
  o.int32_field(5, c.distortion_model);
  o.bytes_field(6, c.reference.data(), c.reference.size());
  o.bytes_field(7, c.img_name.data(), c.img_name.size());
  o.int32_field(8, c.width);
  o.int32_field(9, c.height);
  o.int32_field(10, c.channels);
  return b;
}

std::vector<std::uint8_t> encode_context(const Context& c) {
  check_utf8(c.name, "context.name");
  std::vector<std::uint8_t> b;
  Out o(b);
  o.bytes_field(1, c.name.data(), c.name.size());
  if (c.has_calibration || !calibration_is_default(c.calibration))
    o.message_field(2, encode_calibration(c.calibration));
  o.int32_field(3, c.clusters);
  return b;
}

std::size_t stixel_size(const Stixel& s) {
  return int32_field_size(s.u) + int32_field_size(s.vT) + int32_field_size(s.vB) +
         float_field_size(s.d) + int32_field_size(s.label) + int32_field_size(s.width) +
         float_field_size(s.confidence) + int32_field_size(s.idx) + int32_field_size(s.cluster);
}

}  // namespace

std::vector<std::uint8_t> encode_stx1(const StixelWorld& world) {
  std::size_t total = 0;
  for (const Stixel& s : world.stixels) total += len_field_size(stixel_size(s));
  if (!world.image.empty()) total += len_field_size(world.image.size());
  std::vector<std::uint8_t> context;
  const Context& c = world.context;
  const bool write_context =
      world.has_context || c.has_calibration || !c.name.empty() || c.clusters != 0 ||
      !calibration_is_default(c.calibration);
  if (write_context) {
    context = encode_context(c);
    total += len_field_size(context.size());
  }

  std::vector<std::uint8_t> b;
  b.reserve(total);
  Out o(b);
  for (const Stixel& s : world.stixels) {
    o.tag(1, kLen);
    o.varint(stixel_size(s));
    o.int32_field(1, s.u);
    o.int32_field(2, s.vT);
    o.int32_field(3, s.vB);
    o.float_field(4, s.d);
    o.int32_field(5, s.label);
    o.int32_field(6, s.width);
    o.float_field(7, s.confidence);
    o.int32_field(8, s.idx);
    o.int32_field(9, s.cluster);
  }
  o.bytes_field(2, world.image.data(), world.image.size());
  if (write_context) o.message_field(3, context);
  return b;
}

bool is_valid_utf8(const std::string& s) {
  const auto* p = reinterpret_cast<const unsigned char*>(s.data());
  const std::size_t n = s.size();
  std::size_t i = 0;
  while (i < n) {
    const unsigned c = p[i];
    if (c < 0x80) {
      ++i;
      continue;
    }
    int len;
    std::uint32_t cp;
    if (c >= 0xC2 && c <= 0xDF) {
      len = 2;
      cp = c & 0x1F;
    } else if (c >= 0xE0 && c <= 0xEF) {
      len = 3;
      cp = c & 0x0F;
    } else if (c >= 0xF0 && c <= 0xF4) {
      len = 4;
      cp = c & 0x07;
    } else {
      return false;
    }
    if (n - i < static_cast<std::size_t>(len)) return false;
    for (int k = 1; k < len; ++k) {
      if ((p[i + k] & 0xC0) != 0x80) return false;
      cp = (cp << 6) | (p[i + k] & 0x3F);
    }
    if ((len == 3 && cp < 0x800) || (len == 4 && (cp < 0x10000 || cp > 0x10FFFF)) ||
        (cp >= 0xD800 && cp <= 0xDFFF))
      return false;
    i += len;
  }
  return true;
}

}  // namespace stixel
