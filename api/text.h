// Messages handed to C callers are one printable line: control characters are
// escaped and very long messages cut.
#pragma once

#include <string>

namespace roadnn_api {

std::string one_line(const std::string& text, std::size_t max_bytes = 1000);

}  // namespace roadnn_api
