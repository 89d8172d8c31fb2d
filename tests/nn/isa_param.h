// Runs a parameterised test once per ISA this build and machine support: scalar plus
// AVX2 and AVX-512 on x86-64, scalar plus NEON on aarch64.
#pragma once

#include <gtest/gtest.h>

#include <vector>

#include "nn/isa.h"

namespace nntest {

inline std::vector<nn::Isa> supported_isas() {
  std::vector<nn::Isa> out;
  for (nn::Isa isa : {nn::Isa::Scalar, nn::Isa::Avx2, nn::Isa::Avx512, nn::Isa::Neon})
    if (nn::isa_supported(isa)) out.push_back(isa);
  return out;
}

inline std::string isa_test_name(const testing::TestParamInfo<nn::Isa>& info) {
  return nn::isa_name(info.param);
}

// Sets the active ISA for the test's duration.
class IsaScope {
 public:
  explicit IsaScope(nn::Isa isa) : saved_(nn::active_isa()) { nn::set_isa(isa); }
  ~IsaScope() { nn::set_isa(saved_); }
 private:
  nn::Isa saved_;
};

}  // namespace nntest
