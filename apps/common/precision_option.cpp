#include "apps/common/precision_option.h"

#include "nn/gemm_bf16.h"

namespace apps {

const char* const kPrecisionHelp =
    "f32 (default: matches PyTorch) or bf16 (AVX512_BF16 CPUs: the MLP matrix products in\n"
    "                            bfloat16, less exact; 1.7x faster on AMD Zen 5, slower on Intel CPUs\n"
    "                            without AMX; see docs/PERFORMANCE.md)";

nn::Precision precision_option(cli::Parser& args, const std::string& text) {
  nn::Precision p = nn::Precision::F32;
  if (!text.empty() && !nn::parse_precision(text, &p)) args.fail("--precision must be f32 or bf16");
  if (p == nn::Precision::Bf16 && !nn::bf16_gemm_available())
    args.fail("--precision bf16 needs AVX512_BF16 and the avx512 kernels; this CPU (or --isa / NN_ISA) "
              "does not offer them");
  return p;
}

}  // namespace apps
