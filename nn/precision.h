// The arithmetic a model's large matrix products use. F32 is the default and matches
// PyTorch; Bf16 (AVX512_BF16 only) rounds the GEMM operands to bfloat16 for about twice
// the multiply-add rate, at an accuracy cost the caller opts into (see nn/gemm_bf16.h).
#pragma once

#include <string>

namespace nn {

enum class Precision { F32, Bf16 };

const char* precision_name(Precision p);  // "f32", "bf16"
bool parse_precision(const std::string& text, Precision* out);

}  // namespace nn
