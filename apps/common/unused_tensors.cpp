#include "apps/common/unused_tensors.h"

#include <cstdio>
#include <set>

namespace apps {

void warn_unused_tensors(const char* prog, const weights::SafeTensors& st, const std::vector<std::string>& used,
                         const std::string& what) {
  const std::set<std::string> known(used.begin(), used.end());
  std::vector<std::string> unused;
  for (const auto& n : st.names())
    if (!known.count(n)) unused.push_back(n);
  if (unused.empty()) return;
  std::string list;
  for (std::size_t i = 0; i < unused.size() && i < 8; ++i) list += (i ? ", " : "") + unused[i];
  if (unused.size() > 8) list += ", ...";
  std::fprintf(stderr, "%s: warning: %s: %zu tensors not used by %s: %s\n", prog, st.source().c_str(), unused.size(),
               what.c_str(), list.c_str());
}

}  // namespace apps
