#include "apps/common/cli.h"

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <limits>

namespace cli {

Parser::Parser(std::string prog, std::string usage, std::string summary)
    : prog_(std::move(prog)), usage_(std::move(usage)), summary_(std::move(summary)) {}

void Parser::flag(const std::string& name, const std::string& help, bool* out) {
  Opt o;
  o.name = name;
  o.help = help;
  o.is_flag = true;
  o.set = [out](const std::string&) { *out = true; return true; };
  opts_.push_back(std::move(o));
}

void Parser::option(const std::string& name, const std::string& metavar, const std::string& help,
                    std::string* out) {
  opts_.push_back({name, metavar, help, false, false, false, [out](const std::string& v) {
                     *out = v;
                     return true;
                   }});
}

void Parser::option(const std::string& name, const std::string& metavar, const std::string& help,
                    int* out) {
  opts_.push_back({name, metavar, help, false, false, false, [out](const std::string& v) {
                     if (v.empty()) return false;
                     char* end = nullptr;
                     errno = 0;
                     long x = std::strtol(v.c_str(), &end, 10);
                     if (errno || *end || x < std::numeric_limits<int>::min() ||
                         x > std::numeric_limits<int>::max())
                       return false;
                     *out = static_cast<int>(x);
                     return true;
                   }});
}

void Parser::option(const std::string& name, const std::string& metavar, const std::string& help,
                    double* out) {
  opts_.push_back({name, metavar, help, false, false, false, [out](const std::string& v) {
                     if (v.empty()) return false;
                     char* end = nullptr;
                     errno = 0;
                     double x = std::strtod(v.c_str(), &end);
                     if (errno || *end || x != x) return false;
                     *out = x;
                     return true;
                   }});
}

void Parser::required(const std::string& name) {
  if (Opt* o = find(name)) o->is_required = true;
}

void Parser::positionals(const std::string& metavar, const std::string& help,
                         std::vector<std::string>* out) {
  pos_metavar_ = metavar;
  pos_help_ = help;
  pos_ = out;
}

void Parser::epilog(const std::string& text) { epilog_ = text; }

Parser::Opt* Parser::find(const std::string& name) {
  for (auto& o : opts_)
    if (o.name == name) return &o;
  return nullptr;
}
const Parser::Opt* Parser::find(const std::string& name) const {
  for (auto& o : opts_)
    if (o.name == name) return &o;
  return nullptr;
}

bool Parser::given(const std::string& name) const {
  const Opt* o = find(name);
  return o && o->seen;
}

std::string Parser::help() const {
  std::string s = "usage: " + prog_ + " " + usage_ + "\n\n" + summary_ + "\n\noptions:\n";
  for (const auto& o : opts_) {
    std::string left = "  --" + o.name + (o.is_flag ? "" : " " + o.metavar);
    if (left.size() < 28) left.resize(28, ' ');
    else left += "\n" + std::string(28, ' ');
    s += left + o.help + (o.is_required ? " (required)" : "") + "\n";
  }
  s += "  --help                    show this help and exit\n";
  if (pos_) s += "\n  " + pos_metavar_ + "  " + pos_help_ + "\n";
  if (!epilog_.empty()) s += "\n" + epilog_ + "\n";
  return s;
}

void Parser::fail(const std::string& message) const {
  std::fprintf(stderr, "%s: %s\nTry '%s --help'.\n", prog_.c_str(), message.c_str(), prog_.c_str());
  std::exit(2);
}

void Parser::parse(int argc, char** argv) {
  bool only_positionals = false;
  for (int i = 1; i < argc; ++i) {
    std::string arg = argv[i];
    if (!only_positionals && arg == "--") {
      only_positionals = true;
      continue;
    }
    if (!only_positionals && (arg == "--help" || arg == "-h")) {
      std::fputs(help().c_str(), stdout);
      std::exit(0);
    }
    if (!only_positionals && arg.size() > 2 && arg.compare(0, 2, "--") == 0) {
      std::string name = arg.substr(2), value;
      bool has_value = false;
      auto eq = name.find('=');
      if (eq != std::string::npos) {
        value = name.substr(eq + 1);
        name = name.substr(0, eq);
        has_value = true;
      }
      Opt* o = find(name);
      if (!o) fail("unknown option --" + name);
      if (o->is_flag) {
        if (has_value) fail("--" + name + " takes no value");
      } else if (!has_value) {
        if (i + 1 >= argc) fail("--" + name + " needs a value (" + o->metavar + ")");
        value = argv[++i];
      }
      if (!o->set(value)) fail("invalid value '" + value + "' for --" + name);
      o->seen = true;
      continue;
    }
    if (!pos_) fail("unexpected argument '" + arg + "'");
    pos_->push_back(arg);
  }
  for (const auto& o : opts_)
    if (o.is_required && !o.seen) fail("--" + o.name + " is required");
}

}  // namespace cli
