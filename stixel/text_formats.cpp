#include "stixel/text_formats.h"

#include <charconv>
#include <cmath>
#include <cstring>

#include "stixel/decimal_text.h"
#include "stixel/error.h"
#include "stixel/stx1.h"

namespace stixel {
namespace {

void append_csv_field(std::string& out, const std::string& s) {
  if (s.find_first_of(",\"\r\n") == std::string::npos) {
    out += s;
    return;
  }
  out += '"';
  for (char c : s) {
    if (c == '"') out += '"';
    out += c;
  }
  out += '"';
}

void append_json_string(std::string& out, const std::string& s) {
  static const char* hex = "0123456789abcdef";
  out += '"';
  for (unsigned char c : s) {
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\r': out += "\\r"; break;
      case '\t': out += "\\t"; break;
      case '\b': out += "\\b"; break;
      case '\f': out += "\\f"; break;
      default:
        if (c < 0x20) {
          out += "\\u00";
          out += hex[c >> 4];
          out += hex[c & 15];
        } else {
          out += static_cast<char>(c);
        }
    }
  }
  out += '"';
}

void append_json_float(std::string& out, float f) {
  // JSON readers parse "-0" as the integer 0: keep the sign of zero visible.
  if (f == 0.0f && std::signbit(f))
    out += "-0.0";
  else if (std::isnan(f))
    out += "\"NaN\"";
  else if (std::isinf(f))
    out += f > 0 ? "\"Infinity\"" : "\"-Infinity\"";
  else
    append_float(out, f);
}

std::string base64(const std::vector<std::uint8_t>& b) {
  static const char* tab = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string s;
  s.reserve((b.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 3 <= b.size(); i += 3) {
    const std::uint32_t v = (b[i] << 16) | (b[i + 1] << 8) | b[i + 2];
    s += tab[v >> 18];
    s += tab[(v >> 12) & 63];
    s += tab[(v >> 6) & 63];
    s += tab[v & 63];
  }
  if (i + 1 == b.size()) {
    const std::uint32_t v = b[i] << 16;
    s += tab[v >> 18];
    s += tab[(v >> 12) & 63];
    s += "==";
  } else if (i + 2 == b.size()) {
    const std::uint32_t v = (b[i] << 16) | (b[i + 1] << 8);
    s += tab[v >> 18];
    s += tab[(v >> 12) & 63];
    s += tab[(v >> 6) & 63];
    s += '=';
  }
  return s;
}

// Collects "key": value members of one JSON object, omitting proto3 defaults.
class Members {
 public:
  void int32(const char* key, std::int32_t v) {
    if (!v) return;
    open(key);
    append_int(body_, v);
  }
  void real(const char* key, float f) {
    std::uint32_t bits;
    std::memcpy(&bits, &f, 4);
    if (!bits) return;
    open(key);
    append_json_float(body_, f);
  }
  void str(const char* key, const std::string& s) {
    if (s.empty()) return;
    open(key);
    append_json_string(body_, s);
  }
  void floats(const char* key, const std::vector<float>& v) {
    if (v.empty()) return;
    open(key);
    body_ += '[';
    for (std::size_t i = 0; i < v.size(); ++i) {
      if (i) body_ += ", ";
      append_json_float(body_, v[i]);
    }
    body_ += ']';
  }
  void raw(const char* key, const std::string& json) {
    open(key);
    body_ += json;
  }
  std::string object() const { return "{" + body_ + "}"; }
  bool empty() const { return body_.empty(); }

 private:
  void open(const char* key) {
    if (!body_.empty()) body_ += ", ";
    append_json_string(body_, key);
    body_ += ": ";
  }
  std::string body_;
};

std::string stixel_json(const Stixel& s) {
  Members m;
  m.int32("u", s.u);
  m.int32("vT", s.vT);
  m.int32("vB", s.vB);
  m.real("d", s.d);
  m.int32("label", s.label);
  m.int32("width", s.width);
  m.real("confidence", s.confidence);
  m.int32("idx", s.idx);
  m.int32("cluster", s.cluster);
  return m.object();
}

}  // namespace

std::string to_csv(const StixelWorld& world, const CsvOptions& o) {
  std::string out = o.extended ? "img,u,vT,vB,d,label,p,width,cluster,idx\n" : "img,u,vT,vB,d,label,p\n";
  std::string img;
  append_csv_field(img, o.img.empty() ? world.context.name : o.img);
  out.reserve(out.size() + world.stixels.size() * (img.size() + 40));
  for (const Stixel& s : world.stixels) {
    out += img;
    out += ',';
    append_int(out, s.u);
    out += ',';
    append_int(out, s.vT);
    out += ',';
    append_int(out, s.vB);
    out += ',';
    append_float(out, s.d);
    out += ',';
    append_int(out, s.label);
    out += ',';
    append_float(out, s.confidence);
    if (o.extended) {
      out += ',';
      append_int(out, s.width);
      out += ',';
      append_int(out, s.cluster);
      out += ',';
      append_int(out, s.idx);
    }
    out += '\n';
  }
  return out;
}

std::string to_json(const StixelWorld& world, const JsonOptions& o) {
  // Strings must be UTF-8 for JSON as for protobuf.
  const Context& c = world.context;
  for (const std::string* s : {&c.name, &c.calibration.reference, &c.calibration.img_name})
    if (!is_valid_utf8(*s)) throw Error("json: a context string is not valid UTF-8");
  const std::string nl = o.pretty ? "\n" : "";
  const std::string ind = o.pretty ? "  " : "";

  Members cal;
  cal.floats("K", c.calibration.K);
  cal.floats("T", c.calibration.T);
  cal.floats("R", c.calibration.R);
  cal.floats("D", c.calibration.D);
  cal.int32("DistortionModel", c.calibration.distortion_model);
  cal.str("reference", c.calibration.reference);
  cal.str("imgName", c.calibration.img_name);
  cal.int32("width", c.calibration.width);
  cal.int32("height", c.calibration.height);
  cal.int32("channels", c.calibration.channels);
  Members ctx;
  ctx.str("name", c.name);
  if (c.has_calibration || !cal.empty()) ctx.raw("calibration", cal.object());
  ctx.int32("clusters", c.clusters);

  std::string out = "{";
  bool first = true;
  auto member = [&](const char* key) {
    out += first ? nl : "," + nl;
    first = false;
    out += ind;
    append_json_string(out, key);
    out += ": ";
  };
  if (!world.stixels.empty()) {
    member("stixel");
    out += '[';
    for (std::size_t i = 0; i < world.stixels.size(); ++i) {
      out += i ? "," + nl : nl;
      out += ind + ind + stixel_json(world.stixels[i]);
    }
    out += nl + ind + "]";
  }
  if (o.include_image && !world.image.empty()) {
    member("image");
    out += '"' + base64(world.image) + '"';
  }
  if (world.has_context || !ctx.empty()) {
    member("context");
    out += ctx.object();
  }
  out += nl + "}" + nl;
  return out;
}

}  // namespace stixel
