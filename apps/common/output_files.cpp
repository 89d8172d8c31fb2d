#include "apps/common/output_files.h"

#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <system_error>
#include <utility>

namespace outputs {
namespace {

namespace fs = std::filesystem;

// ---- the process-wide list of temporaries, read by the signal handler ----
//
// Fixed-size, preallocated: the handler may only touch memory that exists and call
// async-signal-safe functions (unlink, sigaction, raise). A slot is free (0), being
// filled (1), listed (2) or taken by the handler (3); the lock-free atomics make the
// state changes visible to a handler on any thread.
constexpr int kSlots = 64;
constexpr std::size_t kPathBytes = 4096;
struct Slot {
  std::atomic<int> state{0};
  char path[kPathBytes];
};
Slot g_slots[kSlots];
std::atomic<int> g_committing{0};   // > 0 while a set is being renamed
std::atomic<int> g_pending{0};      // a signal that arrived then
std::atomic<bool> g_installed{false};
constexpr int kSignals[] = {SIGINT, SIGTERM, SIGHUP};
static_assert(std::atomic<int>::is_always_lock_free, "the signal handler needs lock-free atomics");

void list_temporary(const std::string& name) {
  if (name.size() >= kPathBytes) throw Error(name + ": temporary file name too long");
  for (Slot& s : g_slots) {
    int expected = 0;
    if (s.state.compare_exchange_strong(expected, 1)) {
      std::memcpy(s.path, name.c_str(), name.size() + 1);
      s.state.store(2);
      return;
    }
  }
  throw Error(name + ": more than " + std::to_string(kSlots) + " temporary files at once");
}

void unlist_temporary(const std::string& name) {
  for (Slot& s : g_slots) {
    if (s.state.load() == 2 && std::strcmp(s.path, name.c_str()) == 0) {
      int expected = 2;
      s.state.compare_exchange_strong(expected, 0);
      return;
    }
  }
}

// Async-signal-safe.
void remove_listed_temporaries() {
  for (Slot& s : g_slots) {
    int expected = 2;
    if (s.state.compare_exchange_strong(expected, 3)) ::unlink(s.path);
  }
}

// Async-signal-safe: the default action for `sig`, then `sig` again.
void die_of(int sig) {
  struct sigaction dfl;
  std::memset(&dfl, 0, sizeof dfl);
  dfl.sa_handler = SIG_DFL;
  sigemptyset(&dfl.sa_mask);
  ::sigaction(sig, &dfl, nullptr);
  ::raise(sig);  // delivered when the handler returns (or at once outside it)
}

extern "C" void on_signal(int sig) {
  const int saved_errno = errno;
  g_pending.store(sig);
  // A set being renamed is finished first; commit() looks at g_pending afterwards.
  // (seq_cst on both sides: either we see the commit has ended or it sees g_pending.)
  if (g_committing.load() == 0) {
    remove_listed_temporaries();
    die_of(sig);
  }
  errno = saved_errno;
}

struct CommitScope {
  CommitScope() { g_committing.fetch_add(1); }
  ~CommitScope() {
    if (g_committing.fetch_sub(1) == 1) {
      const int sig = g_pending.load();
      if (sig != 0 && g_installed.load()) {
        remove_listed_temporaries();
        die_of(sig);
      }
    }
  }
};

std::string errno_text(int err) { return std::generic_category().message(err); }

// ---- identity of a path for the plan ----
struct Identity {
  bool exists = false;
  dev_t dev = 0;
  ino_t ino = 0;
  std::string canonical;
};

Identity identity_of(const std::string& path) {
  Identity id;
  struct stat st;
  if (::stat(path.c_str(), &st) == 0) {
    id.exists = true;
    id.dev = st.st_dev;
    id.ino = st.st_ino;
  }
  std::error_code ec;
  fs::path abs = fs::absolute(path, ec);
  if (ec) abs = fs::path(path);
  fs::path canon = fs::weakly_canonical(abs, ec);
  id.canonical = (ec ? abs : canon).lexically_normal().string();
  return id;
}

}  // namespace

// ---- Plan ----

void Plan::input(const std::string& path, const std::string& role) { inputs_.push_back({path, role}); }

void Plan::output(const std::string& path, const std::string& from) { outputs_.push_back({path, from}); }

void Plan::check() const {
  std::map<std::string, std::size_t> input_by_name, output_by_name;
  std::map<std::pair<dev_t, ino_t>, std::size_t> input_by_inode, output_by_inode;
  for (std::size_t i = 0; i < inputs_.size(); ++i) {
    Identity id = identity_of(inputs_[i].path);
    input_by_name.emplace(id.canonical, i);
    if (id.exists) input_by_inode.emplace(std::make_pair(id.dev, id.ino), i);
  }
  for (std::size_t o = 0; o < outputs_.size(); ++o) {
    const Entry& out = outputs_[o];
    Identity id = identity_of(out.path);
    const auto inode = std::make_pair(id.dev, id.ino);
    std::size_t hit = inputs_.size();
    if (auto it = input_by_name.find(id.canonical); it != input_by_name.end()) hit = it->second;
    else if (id.exists)
      if (auto jt = input_by_inode.find(inode); jt != input_by_inode.end()) hit = jt->second;
    if (hit < inputs_.size())
      throw Error("output " + out.path + " would overwrite the " + inputs_[hit].note + " " + inputs_[hit].path);
    hit = outputs_.size();
    if (auto it = output_by_name.find(id.canonical); it != output_by_name.end()) hit = it->second;
    else if (id.exists)
      if (auto jt = output_by_inode.find(inode); jt != output_by_inode.end()) hit = jt->second;
    if (hit < outputs_.size()) {
      const Entry& first = outputs_[hit];
      std::string msg = "two outputs of this run are both " + first.path;
      if (first.path != out.path) msg += " and " + out.path;
      if (!first.note.empty() && !out.note.empty()) msg += " (from " + first.note + " and " + out.note + ")";
      throw Error(msg);
    }
    output_by_name.emplace(id.canonical, o);
    if (id.exists) output_by_inode.emplace(inode, o);
  }
}

// ---- FileSet ----

FileSet::~FileSet() { discard(); }

void FileSet::add(const std::string& path, const void* data, std::size_t size) {
  add(path, std::vector<weights::ByteSpan>{{data, size}});
}

void FileSet::add(const std::string& path, const std::vector<weights::ByteSpan>& pieces) {
  if (path.empty()) {
    discard();
    throw Error("empty output path");
  }
  if (path.back() == '/') {
    discard();
    throw Error(path + ": output path names a folder, not a file");
  }
  std::string tmp, problem;
  try {
    problem = weights::write_temporary_file(path, pieces, &tmp, &temporary_file_hooks());
  } catch (...) {
    discard();
    throw;
  }
  if (!problem.empty()) {
    discard();
    throw Error(path + ": " + problem);
  }
  files_.push_back({path, tmp});
}

void FileSet::discard() {
  for (const Pending& p : files_) {
    ::unlink(p.temporary.c_str());
    unlist_temporary(p.temporary);
  }
  files_.clear();
}

void FileSet::commit() {
  std::vector<Pending> files = std::move(files_);
  files_.clear();
  std::size_t failed = files.size();
  int err = 0;
  {
    CommitScope scope;  // a signal now waits until the scope ends
    for (std::size_t i = 0; i < files.size(); ++i) {
      if (::rename(files[i].temporary.c_str(), files[i].path.c_str()) != 0) {
        err = errno;
        failed = i;
        break;
      }
    }
    for (std::size_t i = failed; i < files.size(); ++i) ::unlink(files[i].temporary.c_str());
    for (const Pending& p : files) unlist_temporary(p.temporary);
  }
  if (failed == files.size()) return;
  std::string msg = files[failed].path + ": cannot write (cannot rename the temporary file into place: " +
                    errno_text(err) + ")";
  if (files.size() > 1) {
    std::string written, not_written;
    for (std::size_t i = 0; i < files.size(); ++i) {
      std::string& list = i < failed ? written : not_written;
      list += (list.empty() ? "" : ", ") + files[i].path;
    }
    msg += "; this run's set is incomplete: " + (written.empty() ? std::string("none") : written) +
           " replaced, " + not_written + " not";
  }
  throw Error(msg);
}

void write_file(const std::string& path, const void* data, std::size_t size) {
  FileSet set;
  set.add(path, data, size);
  set.commit();
}

// ---- signals ----

void install_interrupt_cleanup() {
  if (g_installed.exchange(true)) return;
  for (int sig : kSignals) {
    struct sigaction old;
    if (::sigaction(sig, nullptr, &old) != 0) continue;
    if (!(old.sa_flags & SA_SIGINFO) && old.sa_handler == SIG_IGN) continue;  // e.g. nohup: leave it ignored
    struct sigaction sa;
    std::memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    for (int other : kSignals) sigaddset(&sa.sa_mask, other);
    sa.sa_flags = SA_RESTART;
    ::sigaction(sig, &sa, nullptr);
  }
}

const weights::TemporaryFileHooks& temporary_file_hooks() {
  static const weights::TemporaryFileHooks hooks{list_temporary, unlist_temporary};
  return hooks;
}

std::size_t temporaries_listed() {
  std::size_t n = 0;
  for (const Slot& s : g_slots) n += s.state.load() == 2;
  return n;
}

}  // namespace outputs
