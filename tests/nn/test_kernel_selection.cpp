// Which kernels run: the engine's choice of ISA, kernel table and GEMM micro-kernel,
// checked against what the architecture and the CPU say it must be. The CPU is read
// here from /proc/cpuinfo, independently of nn/cpu_features (the engine's only probe).
// On aarch64 (a board, or qemu-aarch64 in scripts/test_arm64) the answer is NEON:
// Advanced SIMD is part of the architecture.
#include <gtest/gtest.h>

#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "nn/gemm.h"
#include "nn/isa.h"
#include "nn/kernel_table.h"
#include "tests/nn/isa_param.h"
#include "tests/nn/random_data.h"

namespace {

#if defined(__x86_64__)
// The x86 feature flags of the first processor in /proc/cpuinfo.
std::set<std::string> x86_flags() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("flags", 0) != 0) continue;
    std::istringstream words(line.substr(line.find(':') + 1));
    std::set<std::string> out;
    for (std::string w; words >> w;) out.insert(w);
    return out;
  }
  return {};
}
#endif

// The ISA the engine must pick by default on this machine.
nn::Isa expected_best_isa() {
#if defined(__aarch64__)
  return nn::Isa::Neon;
#elif defined(__x86_64__)
  const std::set<std::string> f = x86_flags();
  EXPECT_FALSE(f.empty()) << "no flags line in /proc/cpuinfo";
  auto has = [&](std::initializer_list<const char*> names) {
    for (const char* n : names)
      if (!f.count(n)) return false;
    return true;
  };
  if (has({"avx2", "fma", "f16c", "avx512f", "avx512bw", "avx512dq", "avx512vl"})) return nn::Isa::Avx512;
  if (has({"avx2", "fma", "f16c"})) return nn::Isa::Avx2;
  return nn::Isa::Scalar;
#else
  return nn::Isa::Scalar;
#endif
}

TEST(KernelSelection, DefaultIsTheBestIsaOfTheCpu) {
  const nn::Isa want = expected_best_isa();
  EXPECT_EQ(nn::isa_name(nn::detect_isa()), std::string(nn::isa_name(want)));
  EXPECT_EQ(nn::active_isa(), want) << "a thread with default options runs the best kernels";
  EXPECT_EQ(nn::kernel_table(nn::active_isa()).isa, want);
  // The parameterised kernel tests run every ISA of the architecture, scalar first.
  const std::vector<nn::Isa> isas = nntest::supported_isas();
  ASSERT_FALSE(isas.empty());
  EXPECT_EQ(isas.front(), nn::Isa::Scalar);
  EXPECT_EQ(isas.back(), want);
#if defined(__aarch64__)
  EXPECT_EQ(isas, (std::vector<nn::Isa>{nn::Isa::Scalar, nn::Isa::Neon}));
#endif
}

TEST(KernelSelection, EachIsaHasItsOwnTable) {
  for (nn::Isa isa : nntest::supported_isas()) {
    SCOPED_TRACE(nn::isa_name(isa));
    const nn::KernelTable& t = nn::kernel_table(isa);
    EXPECT_EQ(t.isa, isa);
    const int lanes = isa == nn::Isa::Avx512 ? 16 : isa == nn::Isa::Avx2 ? 8 : isa == nn::Isa::Neon ? 4 : 1;
    EXPECT_EQ(t.lanes, lanes);
    EXPECT_NE(t.apply_act, nullptr);
    EXPECT_NE(t.layernorm_rows, nullptr);
    EXPECT_NE(t.winograd_input_tile, nullptr);
    EXPECT_NE(t.roi_bin, nullptr);
    if (isa != nn::Isa::Scalar) {
      EXPECT_NE(t.apply_act, nn::kernel_table(nn::Isa::Scalar).apply_act) << "the vector table holds scalar code";
    }
  }
}

// A cap names a level: the other architecture's names select this one's ISA of that level.
TEST(KernelSelection, CapsMapToTheArchitecturesIsa) {
  EXPECT_EQ(nn::cap_isa(nn::Isa::Scalar), nn::Isa::Scalar);
#if defined(__aarch64__)
  EXPECT_EQ(nn::cap_isa(nn::Isa::Avx2), nn::Isa::Neon);
  EXPECT_EQ(nn::cap_isa(nn::Isa::Avx512), nn::Isa::Neon);
  EXPECT_EQ(nn::cap_isa(nn::Isa::Neon), nn::Isa::Neon);
  EXPECT_FALSE(nn::isa_supported(nn::Isa::Avx2));
  EXPECT_FALSE(nn::isa_supported(nn::Isa::Avx512));
#elif defined(__x86_64__)
  const nn::Isa best = expected_best_isa();
  EXPECT_FALSE(nn::isa_supported(nn::Isa::Neon));
  EXPECT_EQ(nn::cap_isa(nn::Isa::Neon), best == nn::Isa::Scalar ? nn::Isa::Scalar : nn::Isa::Avx2);
  EXPECT_EQ(nn::cap_isa(nn::Isa::Avx512), best);
#endif
  nn::Isa parsed = nn::Isa::Scalar;
  ASSERT_TRUE(nn::parse_isa("neon", &parsed));
  EXPECT_EQ(parsed, nn::Isa::Neon);
}

// ConvNeXt-Tiny's MLP GEMMs (K 96 -> N 384, 384 -> 96, ..., 768 -> 3072) pack for a
// micro-kernel of the active ISA, and its name says so.
TEST(KernelSelection, ConvNeXtGemmRunsTheIsasMicroKernel) {
  const nn::Isa isa = nn::active_isa();
  const std::string want = nn::isa_name(expected_best_isa());
  for (int dim : {96, 192, 384, 768}) {
    for (const auto& [n, k] : {std::pair<int, int>{4 * dim, dim}, std::pair<int, int>{dim, 4 * dim}}) {
      SCOPED_TRACE("N " + std::to_string(n) + " K " + std::to_string(k));
      const std::string name = nn::gemm_kernel_name(isa, n);
      EXPECT_NE(name.find(want), std::string::npos) << name;
      const std::vector<float> w = nntest::random_vector(static_cast<std::size_t>(n) * k, 5);
      const nn::GemmWeights packed = nn::GemmWeights::pack(w.data(), n, k);
      EXPECT_EQ(packed.isa(), expected_best_isa());
      EXPECT_EQ(nn::gemm_ukernel(packed.ukernel()).name, name);
    }
  }
#if defined(__x86_64__)
  if (expected_best_isa() == nn::Isa::Avx512) {
    EXPECT_STREQ(nn::gemm_kernel_name(isa, 384), "gemm_f32_8x48_avx512");
  }
#endif
}

}  // namespace
