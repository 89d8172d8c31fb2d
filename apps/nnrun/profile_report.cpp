#include "apps/nnrun/profile_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace nnrun {
namespace {

struct Row {
  const nn::ProfileEntry* e;
  const char* level;
  double min, median, max, gflops, pct;
};

std::vector<Row> rows_of(const ProfileRun& run, const std::vector<ProfileTable>& tables) {
  std::vector<Row> rows;
  for (const auto& t : tables)
    for (const auto& e : t.profiler->entries()) {
      if (!e.calls) continue;
      // Samples when reserved (every timed call); else the mean stands for all three.
      const std::vector<double> s = e.samples.empty() ? std::vector<double>{e.total_ms / e.calls} : e.samples;
      Row r{&e, t.level, *std::min_element(s.begin(), s.end()), median_of(s), *std::max_element(s.begin(), s.end()),
            0, 0};
      if (e.flops > 0 && r.median > 0) r.gflops = e.flops / (r.median * 1e6);
      if (run.peak_gflops > 0) r.pct = 100.0 * r.gflops / run.peak_gflops;
      rows.push_back(r);
    }
  return rows;
}

std::string json_string(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", c);
      out += buf;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

// JSON has no NaN or Inf.
std::string num(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

}  // namespace

double median_of(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

std::string profile_json(const ProfileRun& run, const std::vector<ProfileTable>& tables) {
  std::string o = "{\n";
  o += "  \"model\": " + json_string(run.model) + ",\n";
  o += "  \"isa\": " + json_string(run.isa) + ",\n";
  o += "  \"threads\": " + std::to_string(run.threads) + ",\n";
  o += "  \"passes\": " + std::to_string(run.passes) + ",\n";
  o += "  \"peak_gflops\": " + num(run.peak_gflops) + ",\n";
  o += "  \"forward_ms\": {\"min\": " + num(run.forward_min) + ", \"median\": " + num(run.forward_median) +
       ", \"max\": " + num(run.forward_max) + "},\n";
  o += "  \"layers\": [";
  bool first = true;
  for (const Row& r : rows_of(run, tables)) {
    o += first ? "\n" : ",\n";
    first = false;
    const nn::ProfileEntry& e = *r.e;
    o += "    {\"name\": " + json_string(e.layer) + ", \"level\": " + json_string(r.level) +
         ", \"op\": " + json_string(e.op) + ", \"shape\": " + json_string(e.shape) + ", \"flops\": " + num(e.flops) +
         ", \"bytes\": " + (e.bytes > 0 ? num(e.bytes) : "null") + ", \"calls\": " + std::to_string(e.calls) +
         ", \"ms_min\": " + num(r.min) + ", \"ms_median\": " + num(r.median) + ", \"ms_max\": " + num(r.max) +
         ", \"gflops\": " + (e.flops > 0 ? num(r.gflops) : "null") +
         ", \"pct_peak\": " + (e.flops > 0 && run.peak_gflops > 0 ? num(r.pct) : "null") + "}";
  }
  o += "\n  ]\n}\n";
  return o;
}

std::string profile_csv(const ProfileRun& run, const std::vector<ProfileTable>& tables) {
  std::string o = "name,level,op,shape,flops,bytes,calls,ms_min,ms_median,ms_max,gflops,pct_peak\n";
  for (const Row& r : rows_of(run, tables)) {
    const nn::ProfileEntry& e = *r.e;
    o += csv_field(e.layer) + "," + r.level + "," + csv_field(e.op) + "," + csv_field(e.shape) + "," + num(e.flops) +
         "," + (e.bytes > 0 ? num(e.bytes) : "") + "," + std::to_string(e.calls) + "," + num(r.min) + "," +
         num(r.median) + "," + num(r.max) + "," + (e.flops > 0 ? num(r.gflops) : "") + "," +
         (e.flops > 0 && run.peak_gflops > 0 ? num(r.pct) : "") + "\n";
  }
  return o;
}

}  // namespace nnrun
