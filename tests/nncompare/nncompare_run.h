// Runs the nncompare binary in a test's temporary folder and collects its exit code,
// stdout and stderr (shared by the CLI tests and the perturbed-checkpoint test).
#pragma once

#include <sys/wait.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

namespace nncompare_test {

struct Result {
  int code = -1;
  std::string out, err;
};

// `args` is appended to the command line as is (the caller quotes); outputs go to
// files in `dir`.
inline Result run(const std::string& dir, const std::string& args) {
  const std::string cmd = std::string(NNCOMPARE_PATH) + " " + args + " >" + dir + "/stdout 2>" + dir + "/stderr";
  Result r;
  const int status = std::system(cmd.c_str());
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::stringstream o, e;
  o << std::ifstream(dir + "/stdout").rdbuf();
  e << std::ifstream(dir + "/stderr").rdbuf();
  r.out = o.str();
  r.err = e.str();
  return r;
}

}  // namespace nncompare_test
