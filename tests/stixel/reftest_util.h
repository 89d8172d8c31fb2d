// Loading the reference files tests/reference/stixel_*.py write at test time.
#pragma once

#include "stixel/world.h"

#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "weights/safetensors.h"

namespace stxref {

inline std::string ref_path(const std::string& file) { return std::string(ROADNN_REF_DIR) + "/" + file; }

// Loads a reference file; a missing file means its generator (ctest fixture
// ref_stixel_*) failed or did not run.
inline weights::SafeTensors load_path(const std::string& path) {
  if (!std::ifstream(path))
    throw std::runtime_error(path + " is missing: its generator tests/reference/stixel_*.py (ctest fixture "
                             "ref_stixel_*) failed or did not run; it needs numpy, and for .stx1 files "
                             "protobuf-compiler and python3-protobuf, for /usr/bin/python3");
  return weights::SafeTensors::load(path);
}

inline weights::SafeTensors load(const std::string& file) { return load_path(ref_path(file)); }

inline std::vector<double> f64(const weights::SafeTensors& st, const std::string& name) {
  const auto& info = st.info(name);
  EXPECT_EQ(info.dtype, weights::DType::F64) << name;
  std::vector<double> v(static_cast<std::size_t>(info.numel()));
  std::memcpy(v.data(), st.raw(name), v.size() * sizeof(double));
  return v;
}

inline std::vector<std::uint8_t> u8(const weights::SafeTensors& st, const std::string& name) {
  const auto& info = st.info(name);
  EXPECT_EQ(info.dtype, weights::DType::U8) << name;
  const std::uint8_t* p = st.raw(name);
  return std::vector<std::uint8_t>(p, p + info.numel());
}

inline std::vector<int> i32(const weights::SafeTensors& st, const std::string& name) {
  std::vector<int> out;
  for (std::int64_t v : st.i64(name)) out.push_back(static_cast<int>(v));
  return out;
}

inline std::string meta(const weights::SafeTensors& st, const std::string& key) {
  auto it = st.metadata().find(key);
  if (it == st.metadata().end()) throw std::runtime_error(st.source() + ": no metadata '" + key + "'");
  return it->second;
}

// The stixels a reference script stored as parallel columns u, vT, vB, d, width,
// confidence, cluster.
inline std::vector<stixel::Stixel> stixels(const weights::SafeTensors& st) {
  const auto u = i32(st, "u"), vT = i32(st, "vT"), vB = i32(st, "vB");
  const auto width = i32(st, "width"), cluster = i32(st, "cluster");
  const auto d = st.f32("d"), conf = st.f32("confidence");
  std::vector<stixel::Stixel> out;
  for (std::size_t i = 0; i < u.size(); ++i) {
    stixel::Stixel s;
    s.u = u[i];
    s.vT = vT[i];
    s.vB = vB[i];
    s.d = d[i];
    s.width = width[i];
    s.confidence = conf[i];
    s.cluster = cluster[i];
    out.push_back(s);
  }
  return out;
}

}  // namespace stxref
