// Field helpers of the small text formats SHLE reads (boxes CSV, the per-scene
// truth table): one definition of "blank" and of "a number", so every reader
// accepts and refuses the same text.
#pragma once

#include <string_view>

namespace shle {

// `s` without leading blanks/tabs and trailing blanks/tabs/CR.
std::string_view trim_field(std::string_view s);

// A plain decimal number ("12", "-0.5", "3e2") of at most 64 characters; false for
// anything else, including what strtod alone would take ("inf", "nan", hex).
bool parse_decimal(std::string_view t, double* out);

}  // namespace shle
