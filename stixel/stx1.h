// .stx1 files: the raw proto3 binary serialisation of one pyStixel-lib
// StixelWorld message (no header, no length prefix, no compression).
//
// The writer emits exactly what the protobuf library emits for the same message:
// fields in field-number order, proto3 defaults omitted (a float is omitted only
// if it is +0.0), repeated floats packed, negative int32 as 10-byte varints,
// empty sub-messages written only when marked present. The reader is bounds-
// checked and accepts what protobuf accepts: any field order, unknown fields
// (skipped, groups included), packed or unpacked repeated floats, the last value
// of a repeated singular scalar, merged repeated sub-messages. It is stricter in
// one way: a known field with the wrong wire type is an error (the file is
// damaged), where protobuf would silently keep it as an unknown field.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "stixel/world.h"

namespace stixel {

// Throws Error if a string field is not valid UTF-8 (protobuf readers reject it).
std::vector<std::uint8_t> encode_stx1(const StixelWorld& world);

// Throws Error "<source>: byte N: <problem>" for malformed input.
StixelWorld decode_stx1(const std::uint8_t* data, std::size_t size, const std::string& source);

// Reads and decodes a file (up to 2 GiB); errors name the path.
StixelWorld read_stx1(const std::string& path);

// True if s is valid UTF-8 (no overlongs, surrogates or code points > U+10FFFF).
bool is_valid_utf8(const std::string& s);

}  // namespace stixel
