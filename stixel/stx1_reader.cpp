// Bounds-checked proto3 wire-format reader for StixelWorld. Every read checks
// the remaining bytes of the enclosing message first; errors give the byte
// offset in the file and the field.

#include <cstring>

#include "stixel/error.h"
#include "stixel/stx1.h"
#include "weights/file_io.h"

namespace stixel {
namespace {

enum WireType { kVarint = 0, kFixed64 = 1, kLen = 2, kStartGroup = 3, kEndGroup = 4, kFixed32 = 5 };

const char* wire_type_name(int wt) {
  switch (wt) {
    case kVarint: return "varint";
    case kFixed64: return "fixed64";
    case kLen: return "length-delimited";
    case kStartGroup: return "start-group";
    case kEndGroup: return "end-group";
    case kFixed32: return "fixed32";
    default: return "invalid";
  }
}

constexpr int kMaxGroupDepth = 64;

class Reader {
 public:
  Reader(const std::uint8_t* data, std::size_t size, const std::string& source)
      : p_(data), size_(size), source_(source) {}

  [[noreturn]] void fail(std::size_t at, const std::string& what) const {
    throw Error(source_ + ": byte " + std::to_string(at) + ": " + what);
  }

  std::uint64_t varint(std::size_t& pos, std::size_t end, const char* what) const {
    const std::size_t start = pos;
    std::uint64_t v = 0;
    for (int i = 0; i < 10; ++i) {
      if (pos >= end) fail(start, std::string("truncated varint in ") + what);
      const std::uint8_t b = p_[pos++];
      v |= static_cast<std::uint64_t>(b & 0x7F) << (7 * i);
      if (!(b & 0x80)) return v;
    }
    fail(start, std::string("malformed varint (more than 10 bytes) in ") + what);
  }

  std::uint32_t fixed32(std::size_t& pos, std::size_t end, const char* what) const {
    if (end - pos < 4) fail(pos, std::string("truncated fixed32 in ") + what);
    std::uint32_t v = 0;
    for (int k = 0; k < 4; ++k) v |= static_cast<std::uint32_t>(p_[pos + k]) << (8 * k);
    pos += 4;
    return v;
  }

  float f32(std::size_t& pos, std::size_t end, const char* what) const {
    const std::uint32_t bits = fixed32(pos, end, what);
    float f;
    std::memcpy(&f, &bits, 4);
    return f;
  }

  // Length prefix of a length-delimited field; returns the end of its payload.
  std::size_t length(std::size_t& pos, std::size_t end, const char* what) const {
    const std::size_t at = pos;
    const std::uint64_t n = varint(pos, end, what);
    if (n > end - pos)
      fail(at, std::string("length ") + std::to_string(n) + " of " + what + " runs past the end (" +
                   std::to_string(end - pos) + " bytes left)");
    return pos + static_cast<std::size_t>(n);
  }

  struct Tag {
    int field;
    int wire;
    std::size_t at;
  };

  Tag tag(std::size_t& pos, std::size_t end, const char* message) const {
    const std::size_t at = pos;
    const std::uint64_t t = varint(pos, end, message);
    const std::uint64_t field = t >> 3;
    const int wire = static_cast<int>(t & 7);
    if (field == 0 || field > 536870911)
      fail(at, std::string("invalid field number ") + std::to_string(field) + " in " + message);
    if (wire > 5) fail(at, std::string("invalid wire type ") + std::to_string(wire) + " in " + message);
    if (wire == kEndGroup) fail(at, std::string("unexpected end-group in ") + message);
    return {static_cast<int>(field), wire, at};
  }

  // Skips an unknown field whose tag has been read.
  void skip(const Tag& t, std::size_t& pos, std::size_t end, const char* message, int depth = 0) const {
    switch (t.wire) {
      case kVarint: varint(pos, end, message); return;
      case kFixed64:
        if (end - pos < 8) fail(pos, std::string("truncated fixed64 in ") + message);
        pos += 8;
        return;
      case kLen: pos = length(pos, end, message); return;
      case kFixed32: fixed32(pos, end, message); return;
      case kStartGroup: {
        if (depth >= kMaxGroupDepth) fail(t.at, std::string("groups nested too deeply in ") + message);
        for (;;) {
          const std::size_t at = pos;
          const std::uint64_t raw = varint(pos, end, message);
          const int wire = static_cast<int>(raw & 7);
          const std::uint64_t field = raw >> 3;
          if (wire == kEndGroup) {
            if (field != static_cast<std::uint64_t>(t.field))
              fail(at, std::string("mismatched end-group in ") + message);
            return;
          }
          if (field == 0 || wire > 5) fail(at, std::string("malformed group in ") + message);
          skip({static_cast<int>(field), wire, at}, pos, end, message, depth + 1);
        }
      }
      default: fail(t.at, std::string("invalid wire type in ") + message);
    }
  }

  [[noreturn]] void wrong_type(const Tag& t, const char* field, int expected) const {
    fail(t.at, std::string("field ") + field + " has wire type " + std::to_string(t.wire) + " (" +
                   wire_type_name(t.wire) + "), expected " + std::to_string(expected) + " (" +
                   wire_type_name(expected) + ")");
  }

  std::int32_t int32_field(const Tag& t, std::size_t& pos, std::size_t end, const char* field) const {
    if (t.wire != kVarint) wrong_type(t, field, kVarint);
    // int32 keeps the low 32 bits of the varint, as protobuf does.
    return static_cast<std::int32_t>(static_cast<std::uint32_t>(varint(pos, end, field)));
  }

  float float_field(const Tag& t, std::size_t& pos, std::size_t end, const char* field) const {
    if (t.wire != kFixed32) wrong_type(t, field, kFixed32);
    return f32(pos, end, field);
  }

  std::string string_field(const Tag& t, std::size_t& pos, std::size_t end, const char* field) const {
    if (t.wire != kLen) wrong_type(t, field, kLen);
    const std::size_t stop = length(pos, end, field);
    std::string s(reinterpret_cast<const char*>(p_ + pos), stop - pos);
    if (!is_valid_utf8(s)) fail(t.at, std::string("field ") + field + " is not valid UTF-8");
    pos = stop;
    return s;
  }

  // Packed (one length-delimited record) or unpacked (one fixed32 per value).
  void repeated_float(const Tag& t, std::size_t& pos, std::size_t end, const char* field,
                      std::vector<float>& out) const {
    if (t.wire == kFixed32) {
      out.push_back(f32(pos, end, field));
      return;
    }
    if (t.wire != kLen) wrong_type(t, field, kLen);
    const std::size_t stop = length(pos, end, field);
    if ((stop - pos) % 4 != 0)
      fail(t.at, std::string("packed ") + field + " has " + std::to_string(stop - pos) +
                     " bytes, not a multiple of 4");
    while (pos < stop) out.push_back(f32(pos, stop, field));
  }

  std::size_t message_field(const Tag& t, std::size_t& pos, std::size_t end, const char* field) const {
    if (t.wire != kLen) wrong_type(t, field, kLen);
    return length(pos, end, field);
  }

  void stixel(std::size_t pos, std::size_t end, Stixel& s) const {
    while (pos < end) {
      const Tag t = tag(pos, end, "Stixel");
      switch (t.field) {
        case 1: s.u = int32_field(t, pos, end, "Stixel.u"); break;
        case 2: s.vT = int32_field(t, pos, end, "Stixel.vT"); break;
        case 3: s.vB = int32_field(t, pos, end, "Stixel.vB"); break;
        case 4: s.d = float_field(t, pos, end, "Stixel.d"); break;
        case 5: s.label = int32_field(t, pos, end, "Stixel.label"); break;
        case 6: s.width = int32_field(t, pos, end, "Stixel.width"); break;
        case 7: s.confidence = float_field(t, pos, end, "Stixel.confidence"); break;
        case 8: s.idx = int32_field(t, pos, end, "Stixel.idx"); break;
        case 9: s.cluster = int32_field(t, pos, end, "Stixel.cluster"); break;
        default: skip(t, pos, end, "Stixel");
      }
    }
  }

  void calibration(std::size_t pos, std::size_t end, CameraInfo& c) const {
    while (pos < end) {
      const Tag t = tag(pos, end, "CameraInfo");
      switch (t.field) {
        case 1: repeated_float(t, pos, end, "CameraInfo.K", c.K); break;
        case 2: repeated_float(t, pos, end, "CameraInfo.T", c.T); break;
        case 3: repeated_float(t, pos, end, "CameraInfo.R", c.R); break;
        case 4: repeated_float(t, pos, end, "CameraInfo.D", c.D); break;
        case 5: c.distortion_model = int32_field(t, pos, end, "CameraInfo.DistortionModel"); break;
        case 6: c.reference = string_field(t, pos, end, "CameraInfo.reference"); break;
        case 7: c.img_name = string_field(t, pos, end, "CameraInfo.img_name"); break;
        case 8: c.width = int32_field(t, pos, end, "CameraInfo.width"); break;
        case 9: c.height = int32_field(t, pos, end, "CameraInfo.height"); break;
        case 10: c.channels = int32_field(t, pos, end, "CameraInfo.channels"); break;
        default: skip(t, pos, end, "CameraInfo");
      }
    }
  }

  void context(std::size_t pos, std::size_t end, Context& c) const {
    while (pos < end) {
      const Tag t = tag(pos, end, "Context");
      switch (t.field) {
        case 1: c.name = string_field(t, pos, end, "Context.name"); break;
        case 2: {
          const std::size_t stop = message_field(t, pos, end, "Context.calibration");
          c.has_calibration = true;
          calibration(pos, stop, c.calibration);  // a repeated sub-message merges
          pos = stop;
          break;
        }
        case 3: c.clusters = int32_field(t, pos, end, "Context.clusters"); break;
        default: skip(t, pos, end, "Context");
      }
    }
  }

  void world(StixelWorld& w) const {
    std::size_t pos = 0;
    const std::size_t end = size_;
    while (pos < end) {
      const Tag t = tag(pos, end, "StixelWorld");
      switch (t.field) {
        case 1: {
          const std::size_t stop = message_field(t, pos, end, "StixelWorld.stixel");
          w.stixels.emplace_back();
          stixel(pos, stop, w.stixels.back());
          pos = stop;
          break;
        }
        case 2: {
          const std::size_t stop = message_field(t, pos, end, "StixelWorld.image");
          w.image.assign(p_ + pos, p_ + stop);
          pos = stop;
          break;
        }
        case 3: {
          const std::size_t stop = message_field(t, pos, end, "StixelWorld.context");
          w.has_context = true;
          context(pos, stop, w.context);
          pos = stop;
          break;
        }
        default: skip(t, pos, end, "StixelWorld");
      }
    }
  }

 private:
  const std::uint8_t* p_;
  std::size_t size_;
  const std::string& source_;
};

}  // namespace

StixelWorld decode_stx1(const std::uint8_t* data, std::size_t size, const std::string& source) {
  if (!data && size) throw Error(source + ": null data");
  StixelWorld w;
  Reader(data, size, source).world(w);
  return w;
}

StixelWorld read_stx1(const std::string& path) {
  // The one reader of outside files: regular files only, opened without blocking.
  weights::FileBuffer bytes;
  const std::string problem = weights::read_file(path, std::uint64_t(1) << 31, &bytes);
  if (!problem.empty()) throw Error(path + ": " + problem);
  return decode_stx1(bytes.data(), bytes.size(), path);
}

}  // namespace stixel
