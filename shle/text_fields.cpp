#include "shle/text_fields.h"

#include <cmath>
#include <cstdlib>
#include <string>

namespace shle {

std::string_view next_line(std::string_view text, std::size_t* pos) {
  const std::size_t nl = text.find('\n', *pos);
  const std::string_view line = text.substr(*pos, nl == std::string_view::npos ? std::string_view::npos : nl - *pos);
  *pos = nl == std::string_view::npos ? text.size() : nl + 1;
  return line;
}

std::string_view trim_field(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

bool parse_decimal(std::string_view t, double* out) {
  if (t.empty() || t.size() > 64) return false;
  for (char c : t)
    if (!((c >= '0' && c <= '9') || c == '.' || c == '-' || c == '+' || c == 'e' || c == 'E')) return false;
  const std::string s(t);
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  if (end != s.c_str() + s.size() || !std::isfinite(v)) return false;
  *out = v;
  return true;
}

}  // namespace shle
