// Helpers for the SHLE tests: a temporary folder removed at the end, file
// writers, a command runner, and a check that an expression throws with a message containing text.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <sys/wait.h>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "weights/safetensors.h"

namespace shletest {

class TempDir {
 public:
  TempDir() {
    std::string tmpl = (std::filesystem::temp_directory_path() / "shle_test_XXXXXX").string();
    char* p = ::mkdtemp(tmpl.data());
    if (!p) throw std::runtime_error("mkdtemp failed");
    path_ = p;
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  std::string path() const { return path_; }
  std::string operator/(const std::string& rel) const { return (std::filesystem::path(path_) / rel).string(); }

 private:
  std::string path_;
};

inline void write_bytes(const std::string& path, const std::vector<std::uint8_t>& bytes) {
  std::filesystem::create_directories(std::filesystem::path(path).parent_path());
  std::ofstream f(path, std::ios::binary);
  f.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

inline void write_text(const std::string& path, const std::string& text) {
  write_bytes(path, std::vector<std::uint8_t>(text.begin(), text.end()));
}

inline std::string slurp(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

// A command's exit code and captured standard output and error.
struct Result {
  int code;
  std::string out, err;
};

// Runs a shell command line with stdout/stderr captured in files of `dir`.
inline Result run(const std::string& args, const TempDir& dir) {
  std::string out = dir / "stdout.txt", err = dir / "stderr.txt";
  int status = std::system((args + " > '" + out + "' 2> '" + err + "'").c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(out), slurp(err)};
}

// A reference file's F64 tensor as doubles (the dtype is checked).
inline std::vector<double> f64(const weights::SafeTensors& st, const std::string& name) {
  const weights::TensorInfo& info = st.info(name);
  EXPECT_EQ(info.dtype, weights::DType::F64) << name;
  std::vector<double> v(static_cast<std::size_t>(info.numel()));
  if (!v.empty()) std::memcpy(v.data(), st.raw(name), 8 * v.size());
  return v;
}

}  // namespace shletest

// EXPECT that `stmt` throws an exception whose what() contains `text`.
#define EXPECT_THROW_MSG(stmt, text)                                                     \
  do {                                                                                   \
    bool thrown_ = false;                                                                \
    try {                                                                                \
      stmt;                                                                              \
    } catch (const std::exception& e_) {                                                 \
      thrown_ = true;                                                                    \
      EXPECT_NE(std::string(e_.what()).find(text), std::string::npos)                    \
          << "message: " << e_.what() << "\nexpected to contain: " << (text);            \
    }                                                                                    \
    EXPECT_TRUE(thrown_) << #stmt " did not throw";                                      \
  } while (0)
