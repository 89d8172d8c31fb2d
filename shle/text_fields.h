// Field helpers of the small text formats SHLE reads (boxes CSV, the per-scene
// truth table): one definition of "blank" and of "a number", so every reader
// accepts and refuses the same text.
#pragma once

#include <cstddef>
#include <string_view>

namespace shle {

// The line of `text` starting at *pos, without its '\n'; *pos moves past it.
std::string_view next_line(std::string_view text, std::size_t* pos);

// `s` without leading blanks/tabs and trailing blanks/tabs/CR.
std::string_view trim_field(std::string_view s);

// A plain decimal number ("12", "-0.5", "3e2") of at most 64 characters; false for
// anything else, including what strtod alone would take ("inf", "nan", hex).
bool parse_decimal(std::string_view t, double* out);

}  // namespace shle
