#include "shle/boxes_csv.h"

#include "weights/quote_name.h"

#include <cmath>
#include <cstdlib>

#include "shle/error.h"
#include "shle/file_read.h"
#include "shle/text_fields.h"

namespace shle {

BoxesFile parse_boxes_csv(std::string_view text, const std::string& source) {
  BoxesFile f;
  std::size_t line_no = 0, pos = 0;
  while (pos < text.size()) {
    const std::string_view line = next_line(text, &pos);
    ++line_no;
    std::string_view t = trim_field(line);
    if (t.empty() || t.front() == '#') continue;
    std::vector<std::string_view> fields;
    std::size_t start = 0;
    while (true) {
      std::size_t comma = t.find(',', start);
      fields.push_back(trim_field(t.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start)));
      if (comma == std::string_view::npos) break;
      start = comma + 1;
    }
    std::string where = source + ": line " + std::to_string(line_no) + ": ";
    if (fields.size() != 6)
      throw Error(where + "expected 6 fields frame,x0,y0,x1,y1,score, got " + std::to_string(fields.size()));
    if (fields[0] == "frame") {
      if (f.count != 0 || fields[1] != "x0" || fields[2] != "y0" || fields[3] != "x1" || fields[4] != "y1" ||
          fields[5] != "score")
        throw Error(where + "unexpected header (want frame,x0,y0,x1,y1,score as the first line)");
      continue;
    }
    std::string_view fr = fields[0];
    if (fr.empty() || fr.size() > 9) throw Error(where + "frame " + weights::quote_name(std::string(fr)) + " is not a frame index");
    int frame = 0;
    for (char c : fr) {
      if (c < '0' || c > '9') throw Error(where + "frame " + weights::quote_name(std::string(fr)) + " is not a frame index");
      frame = frame * 10 + (c - '0');
    }
    double v[5];
    static const char* names[5] = {"x0", "y0", "x1", "y1", "score"};
    for (int i = 0; i < 5; ++i)
      if (!parse_decimal(fields[i + 1], &v[i]))
        throw Error(where + names[i] + " " + weights::quote_name(std::string(fields[i + 1])) + " is not a finite number");
    if (v[2] < v[0] || v[3] < v[1]) throw Error(where + "box has x1 < x0 or y1 < y0");
    f.frames[frame].push_back(Candidate{Box{v[0], v[1], v[2], v[3]}, v[4]});
    ++f.count;
  }
  return f;
}

BoxesFile load_boxes_csv(const std::string& path) {
  std::vector<std::uint8_t> bytes = read_file_bytes(path, 256ull << 20);
  return parse_boxes_csv(std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()), path);
}

}  // namespace shle
