// A small, strict command-line parser shared by the apps: --name value or
// --name=value options, boolean flags, positionals, generated --help, and one-line
// errors ("prog: ...") with exit code 2.
#pragma once

#include <functional>
#include <string>
#include <vector>

namespace cli {

class Parser {
 public:
  Parser(std::string prog, std::string usage, std::string summary);

  void flag(const std::string& name, const std::string& help, bool* out);
  void option(const std::string& name, const std::string& metavar, const std::string& help,
              std::string* out);
  void option(const std::string& name, const std::string& metavar, const std::string& help,
              int* out);
  void option(const std::string& name, const std::string& metavar, const std::string& help,
              double* out);
  // Marks an option as required (must be called after declaring it).
  void required(const std::string& name);
  // Collects positional arguments; without this, any positional is an error.
  void positionals(const std::string& metavar, const std::string& help,
                   std::vector<std::string>* out);
  // Extra text printed at the end of --help (examples, notes).
  void epilog(const std::string& text);

  // Parses argv. On --help prints the help and exits 0; on an error prints
  // "prog: message" and "Try 'prog --help'." to stderr and exits 2.
  void parse(int argc, char** argv);
  // True if the option appeared on the command line.
  bool given(const std::string& name) const;
  std::string help() const;
  [[noreturn]] void fail(const std::string& message) const;

 private:
  struct Opt {
    std::string name, metavar, help;
    bool is_flag = false, is_required = false, seen = false;
    std::function<bool(const std::string&)> set;
  };
  Opt* find(const std::string& name);
  const Opt* find(const std::string& name) const;
  std::string prog_, usage_, summary_, epilog_, pos_metavar_, pos_help_;
  std::vector<Opt> opts_;
  std::vector<std::string>* pos_ = nullptr;
};

}  // namespace cli
