// Output files of the apps: never lose data (issue 12, item 5).
//
//  * A run plans first: it names its inputs and every output it will write, and
//    Plan::check() refuses, before anything is written, an output that is one of the
//    inputs (the same file: device and inode when it exists, else the lexically
//    normalised absolute path, symlinks resolved) or two outputs with one path.
//  * Every output goes to a temporary file beside it and is renamed into place. The
//    outputs that belong together (one image's .stx1 and pictures, shle's three
//    files) form a FileSet: all are written as temporaries first, then all renamed,
//    so a set appears whole or not at all.
//  * Temporaries are listed process-wide; after install_interrupt_cleanup() a
//    SIGINT, SIGTERM or SIGHUP removes them before the program dies (a set being
//    renamed is finished first). The weights library writes through
//    temporary_file_hooks(), so its temporaries are listed too.
#pragma once

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "weights/file_io.h"

namespace outputs {

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& what) : std::runtime_error(what) {}
};

class Plan {
 public:
  // `role` names the input in messages: "input", "weights", "calibration", ...
  void input(const std::string& path, const std::string& role = "input");
  // `from`: the input this output is made from, for messages ("" when none).
  void output(const std::string& path, const std::string& from = "");
  // Throws Error with one line when an output is an input ("output P would overwrite
  // the input Q") or two outputs share a path ("two outputs of this run are both P
  // (from A and B)"). Paths are named as they were given.
  void check() const;

 private:
  struct Entry {
    std::string path, note;
  };
  std::vector<Entry> inputs_, outputs_;
};

// Files written together: add() writes each to a temporary (nothing visible yet),
// commit() renames them all. A set destroyed without commit() removes its
// temporaries. Errors are Error("path: problem"); a failed add() removes the set's
// temporaries.
class FileSet {
 public:
  FileSet() = default;
  FileSet(const FileSet&) = delete;
  FileSet& operator=(const FileSet&) = delete;
  ~FileSet();

  void add(const std::string& path, const void* data, std::size_t size);
  void add(const std::string& path, const std::string& text) { add(path, text.data(), text.size()); }
  void add(const std::string& path, const std::vector<std::uint8_t>& bytes) { add(path, bytes.data(), bytes.size()); }
  void add(const std::string& path, const std::vector<weights::ByteSpan>& pieces);
  // Renames every temporary into place; signals wait until all are. Should a rename
  // fail, the rest are removed and the Error says which files of the set were and
  // were not replaced.
  void commit();
  // Removes the temporaries written so far.
  void discard();
  std::size_t size() const { return files_.size(); }

 private:
  struct Pending {
    std::string path, temporary;
  };
  std::vector<Pending> files_;
};

// A set of one file.
void write_file(const std::string& path, const void* data, std::size_t size);

// SIGINT, SIGTERM and SIGHUP (those not ignored) remove the listed temporaries, then
// the signal takes its default course. Idempotent.
void install_interrupt_cleanup();

// Lists the weights library's temporaries (for weights::Writer::write and friends).
const weights::TemporaryFileHooks& temporary_file_hooks();

// The process-wide list (for tests): temporaries listed right now.
std::size_t temporaries_listed();

}  // namespace outputs
