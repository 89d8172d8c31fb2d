// apply_act throughput per ISA: 16K floats (in L1/L2, the GEMM-epilogue situation) and
// 4M floats (streaming from DRAM).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <string>

#include "nn/activation.h"
#include "nn/buffer.h"
#include "nn/isa.h"

namespace {

void bm_act(benchmark::State& state, nn::Act act, nn::Isa isa, std::size_t count) {
  const nn::Isa saved = nn::active_isa();
  nn::set_isa(isa);
  nn::AlignedBuffer x(count), src(count);
  for (std::size_t i = 0; i < count; ++i)
    src[i] = static_cast<float>(static_cast<int>(i % 2001) - 1000) * 0.006f;  // [-6, 6]
  // The refill is timed too (PauseTiming costs more than it): about 1/8 of the GELU time
  // at 16K floats; repeated in-place GELU would otherwise decay into denormals.
  for (auto _ : state) {
    std::copy(src.data(), src.data() + count, x.data());
    nn::apply_act(act, x.data(), count);
    benchmark::ClobberMemory();
  }
  nn::set_isa(saved);
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * static_cast<int64_t>(count));
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations()) *
                          static_cast<int64_t>(count) * 8);
}

int register_all() {
  const struct { const char* name; nn::Act act; } acts[] = {
      {"gelu", nn::Act::Gelu}, {"sigmoid", nn::Act::Sigmoid}, {"hardswish", nn::Act::HardSwish}};
  for (nn::Isa isa : {nn::Isa::Scalar, nn::Isa::Avx2, nn::Isa::Avx512}) {
    if (!nn::isa_supported(isa)) continue;
    for (const auto& a : acts)
      for (std::size_t count : {std::size_t(1) << 14, std::size_t(1) << 22}) {
        const std::string name = std::string("apply_act/") + a.name + "/" + nn::isa_name(isa) +
                                 "/" + std::to_string(count);
        benchmark::RegisterBenchmark(name.c_str(), bm_act, a.act, isa, count)->UseRealTime();
      }
  }
  return 0;
}

const int kRegistered = register_all();

}  // namespace
