// Resident memory of this process (Linux /proc/self/status), for tests that a
// limit is checked before memory is committed.
#pragma once

#include <cstdio>
#include <cstring>

namespace testutil {

// VmRSS (current) or VmHWM (peak) in KiB; -1 when unavailable.
inline long proc_status_kib(const char* field) {
  std::FILE* f = std::fopen("/proc/self/status", "r");
  if (!f) return -1;
  char line[256];
  long v = -1;
  const std::size_t n = std::strlen(field);
  while (std::fgets(line, sizeof line, f))
    if (std::strncmp(line, field, n) == 0 && line[n] == ':') {
      std::sscanf(line + n + 1, "%ld", &v);
      break;
    }
  std::fclose(f);
  return v;
}

inline long rss_kib() { return proc_status_kib("VmRSS"); }
inline long peak_rss_kib() { return proc_status_kib("VmHWM"); }

}  // namespace testutil
