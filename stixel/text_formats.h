// Text exports of a Stixel World.
#pragma once

#include <string>

#include "stixel/world.h"

namespace stixel {

struct CsvOptions {
  // Value of the `img` column; empty = context.name.
  std::string img;
  // Adds width,cluster,idx after the reader's columns (readers that select
  // columns by name, like pyStixel-lib's read_csv, are unaffected).
  bool extended = false;
};

// pyStixel-lib's current CSV layout: header "img,u,vT,vB,d,label,p", one row per
// stixel; floats in the shortest form that reads back as the same float32.
// The img field is quoted (RFC 4180) only if it needs it.
std::string to_csv(const StixelWorld& world, const CsvOptions& options = {});

struct JsonOptions {
  bool include_image = false;  // the embedded PNG/JPEG as base64 (large)
  bool pretty = true;          // one stixel per line
};

// The proto3 canonical JSON mapping of the StixelWorld message (field names as
// protoc's json_name: vT, vB, imgName, DistortionModel; defaults omitted; enums as
// numbers; NaN/Infinity as strings; bytes as base64), so
// google.protobuf.json_format.Parse reads it back into the same message.
std::string to_json(const StixelWorld& world, const JsonOptions& options = {});

}  // namespace stixel
