// Disparity files. The library parses the headerless SmarterEye `.dat` and PFM;
// 16-bit PNG disparity is decoded by the app and converted here from raw samples.
// Every parser checks sizes before touching data; errors are shle::Error
// "<source>: <problem>".
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "shle/types.h"

namespace shle {

// `.dat`: width*height little-endian uint16, row-major, no header; disparity =
// raw / 2^fraction_bits (raw 0 = invalid). The size must match exactly.
DisparityMap parse_dat(const std::uint8_t* bytes, std::size_t size, int width, int height,
                       int fraction_bits, const std::string& source);
DisparityMap read_dat(const std::string& path, int width, int height, int fraction_bits);

// The fraction bit count encoded in a released file name "disparity_<bits>_...dat"
// (5 for the SmarterEye 1280x720 camera); `fallback` for any other name.
int dat_fraction_bits(const std::string& file_name, int fallback = 5);

// PFM ("Pf", single channel float32): header "Pf\n<w> <h>\n<scale>\n", then w*h
// floats, rows stored bottom to top, little-endian when scale < 0. Colour "PF"
// files are rejected. Non-finite values (PFM's "unknown") stay invalid disparities.
DisparityMap parse_pfm(const std::uint8_t* bytes, std::size_t size, const std::string& source);
DisparityMap read_pfm(const std::string& path);

// 16-bit PNG samples already decoded by the app: disparity = raw / scale.
DisparityMap disparity_from_u16(const std::uint16_t* raw, int width, int height, double scale,
                                const std::string& source);

}  // namespace shle
