// `--precision f32|bf16`, shared by the commands that run ConvNeXt (nnrun, stixelnext).
#pragma once

#include <string>

#include "apps/common/cli.h"
#include "nn/precision.h"

namespace apps {

extern const char* const kPrecisionHelp;

// Parses the option's text ("" = f32); a bad name, or bf16 on a CPU (or --isa / NN_ISA)
// without AVX512_BF16, is a usage error (args.fail: one line, exit 2). Call after --isa
// has been applied.
nn::Precision precision_option(cli::Parser& args, const std::string& text);

}  // namespace apps
