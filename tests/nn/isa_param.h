// Runs a parameterised test once per ISA this machine supports.
#pragma once

#include <gtest/gtest.h>

#include <vector>

#include "nn/isa.h"

namespace nntest {

inline std::vector<nn::Isa> supported_isas() {
  std::vector<nn::Isa> out{nn::Isa::Scalar};
  if (static_cast<int>(nn::detect_isa()) >= static_cast<int>(nn::Isa::Avx2)) out.push_back(nn::Isa::Avx2);
  if (nn::detect_isa() == nn::Isa::Avx512) out.push_back(nn::Isa::Avx512);
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
