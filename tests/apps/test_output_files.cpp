// apps/common/output_files: the output plan (an output that is an input, two outputs
// with one path), file sets written whole or not at all, and the temporaries' removal
// on SIGINT.
#include "apps/common/output_files.h"

#include <gtest/gtest.h>

#include "tests/apps/test_dir.h"
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "weights/safetensors.h"

namespace {

namespace fs = std::filesystem;
using Bytes = std::vector<std::uint8_t>;

using appstest::test_dir;

void write_text(const std::string& path, const std::string& text) { std::ofstream(path, std::ios::binary) << text; }

std::string slurp(const std::string& path) {
  std::stringstream s;
  s << std::ifstream(path, std::ios::binary).rdbuf();
  return s.str();
}

std::vector<std::string> folder_entries(const std::string& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

// The message of the Error that plan.check() throws, "" when it does not.
std::string check_message(const outputs::Plan& plan) {
  try {
    plan.check();
  } catch (const outputs::Error& e) {
    return e.what();
  }
  return "";
}

TEST(OutputFiles, WriteReplacesAndLeavesNoTemporary) {
  std::string dir = test_dir();
  std::string path = dir + "/out.bin";
  Bytes a(1000, 1), b(5, 2);
  outputs::write_file(path, a.data(), a.size());
  EXPECT_EQ(slurp(path), std::string(a.begin(), a.end()));
  outputs::write_file(path, b.data(), b.size());
  EXPECT_EQ(slurp(path), std::string(b.begin(), b.end()));
  outputs::write_file(path, nullptr, 0);
  EXPECT_TRUE(slurp(path).empty());
  EXPECT_EQ(folder_entries(dir), std::vector<std::string>{"out.bin"});
  EXPECT_EQ(outputs::temporaries_listed(), 0u);
  // Permissions follow the umask like an ordinary file, not mkstemp's 0600.
  struct stat st;
  ASSERT_EQ(::stat(path.c_str(), &st), 0);
  mode_t mask = ::umask(0);
  ::umask(mask);
  EXPECT_EQ(st.st_mode & 0777, 0666u & ~mask);
}

TEST(OutputFiles, PlanFindsAnInputUnderAnotherSpelling) {
  std::string dir = test_dir();
  fs::create_directories(dir + "/sub");
  write_text(dir + "/a.txt", "input");
  for (const std::string& spelling :
       {dir + "/a.txt", dir + "/./a.txt", dir + "//a.txt", dir + "/sub/../a.txt", dir + "/nowhere/../a.txt"}) {
    outputs::Plan plan;
    plan.input(dir + "/a.txt");
    plan.output(spelling);
    EXPECT_EQ(check_message(plan), "output " + spelling + " would overwrite the input " + dir + "/a.txt");
  }
  // Relative to the working folder.
  outputs::Plan plan;
  plan.input(dir + "/a.txt", "weights");
  plan.output(fs::relative(dir + "/a.txt").string());
  EXPECT_NE(check_message(plan).find("would overwrite the weights " + dir + "/a.txt"), std::string::npos);
  EXPECT_EQ(slurp(dir + "/a.txt"), "input");
}

TEST(OutputFiles, PlanFindsAnInputThroughASymlinkOrHardLink) {
  std::string dir = test_dir();
  write_text(dir + "/a.txt", "input");
  fs::create_symlink(dir + "/a.txt", dir + "/link.txt");
  fs::create_hard_link(dir + "/a.txt", dir + "/hard.txt");
  fs::create_directory_symlink(dir, dir + "/dirlink");
  for (const std::string& out : {dir + "/link.txt", dir + "/hard.txt", dir + "/dirlink/a.txt"}) {
    outputs::Plan plan;
    plan.input(dir + "/a.txt");
    plan.output(out);
    EXPECT_EQ(check_message(plan), "output " + out + " would overwrite the input " + dir + "/a.txt");
    // And the other way round: the input named through the link.
    outputs::Plan back;
    back.input(out);
    back.output(dir + "/a.txt");
    EXPECT_EQ(check_message(back), "output " + dir + "/a.txt would overwrite the input " + out);
  }
}

TEST(OutputFiles, PlanComparesMissingFilesByNormalisedPath) {
  std::string dir = test_dir();
  outputs::Plan plan;
  plan.input(dir + "/missing.png");  // an input that does not exist (yet) still counts
  plan.output(dir + "/x/../missing.png");
  EXPECT_EQ(check_message(plan), "output " + dir + "/x/../missing.png would overwrite the input " + dir + "/missing.png");
}

TEST(OutputFiles, PlanRefusesTwoOutputsWithOnePath) {
  std::string dir = test_dir();
  outputs::Plan plan;
  plan.input(dir + "/a/same.png");
  plan.input(dir + "/b/same.png");
  plan.output(dir + "/out/same.stx1", dir + "/a/same.png");
  plan.output(dir + "/out/same.stx1", dir + "/b/same.png");
  EXPECT_EQ(check_message(plan), "two outputs of this run are both " + dir + "/out/same.stx1 (from " + dir +
                                     "/a/same.png and " + dir + "/b/same.png)");
  outputs::Plan spelled;
  spelled.output(dir + "/out.csv");
  spelled.output(dir + "/./out.csv");
  EXPECT_EQ(check_message(spelled), "two outputs of this run are both " + dir + "/out.csv and " + dir + "/./out.csv");
  outputs::Plan fine;
  fine.input(dir + "/a/same.png");
  fine.output(dir + "/a/same.stx1", dir + "/a/same.png");
  fine.output(dir + "/a/same_overlay.png", dir + "/a/same.png");
  EXPECT_EQ(check_message(fine), "");
  EXPECT_FALSE(fs::exists(dir + "/out"));  // the plan writes nothing
}

TEST(OutputFiles, SetAppearsOnlyOnCommit) {
  std::string dir = test_dir();
  write_text(dir + "/b.txt", "old b");
  {
    outputs::FileSet set;
    set.add(dir + "/a.txt", std::string("new a"));
    set.add(dir + "/b.txt", std::string("new b"));
    EXPECT_EQ(outputs::temporaries_listed(), 2u);
    EXPECT_FALSE(fs::exists(dir + "/a.txt"));
    EXPECT_EQ(slurp(dir + "/b.txt"), "old b");
    set.commit();
  }
  EXPECT_EQ(slurp(dir + "/a.txt"), "new a");
  EXPECT_EQ(slurp(dir + "/b.txt"), "new b");
  EXPECT_EQ(folder_entries(dir), (std::vector<std::string>{"a.txt", "b.txt"}));
  EXPECT_EQ(outputs::temporaries_listed(), 0u);
  {
    outputs::FileSet abandoned;  // destroyed without commit: nothing changes
    abandoned.add(dir + "/a.txt", std::string("newer a"));
    abandoned.add(dir + "/c.txt", std::string("c"));
  }
  EXPECT_EQ(slurp(dir + "/a.txt"), "new a");
  EXPECT_EQ(folder_entries(dir), (std::vector<std::string>{"a.txt", "b.txt"}));
  EXPECT_EQ(outputs::temporaries_listed(), 0u);
}

TEST(OutputFiles, FailedAddRemovesTheSetsTemporaries) {
  std::string dir = test_dir();
  outputs::FileSet set;
  set.add(dir + "/a.txt", std::string("a"));
  try {
    set.add(dir + "/no_such_folder/b.txt", std::string("b"));
    FAIL() << "no error";
  } catch (const outputs::Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind(dir + "/no_such_folder/b.txt: cannot create", 0), 0u) << e.what();
  }
  EXPECT_EQ(set.size(), 0u);
  EXPECT_TRUE(folder_entries(dir).empty());
  EXPECT_EQ(outputs::temporaries_listed(), 0u);
  EXPECT_THROW(set.add("", std::string("x")), outputs::Error);
  EXPECT_THROW(set.add(dir + "/", std::string("x")), outputs::Error);
}

// A rename that fails (the target is a folder): the rest of the set is removed and the
// message says which files were replaced.
TEST(OutputFiles, FailedRenameSaysWhatWasReplaced) {
  std::string dir = test_dir();
  fs::create_directories(dir + "/b.txt/sub");
  outputs::FileSet set;
  set.add(dir + "/a.txt", std::string("a"));
  set.add(dir + "/b.txt", std::string("b"));
  set.add(dir + "/c.txt", std::string("c"));
  try {
    set.commit();
    FAIL() << "no error";
  } catch (const outputs::Error& e) {
    const std::string msg = e.what();
    EXPECT_EQ(msg.rfind(dir + "/b.txt: cannot write (cannot rename", 0), 0u) << msg;
    EXPECT_NE(msg.find("set is incomplete: " + dir + "/a.txt replaced, " + dir + "/b.txt, " + dir + "/c.txt not"),
              std::string::npos)
        << msg;
    EXPECT_EQ(std::count(msg.begin(), msg.end(), '\n'), 0) << msg;
  }
  EXPECT_EQ(folder_entries(dir), (std::vector<std::string>{"a.txt", "b.txt"}));
  EXPECT_EQ(outputs::temporaries_listed(), 0u);
}

// The weights library's writer lists its temporary while it exists.
TEST(OutputFiles, HooksListTheLibrarysTemporary) {
  std::string dir = test_dir();
  std::vector<std::string> seen;
  weights::TemporaryFileHooks hooks;
  hooks.creating = [&](const std::string& t) {
    seen.push_back(t);
    outputs::temporary_file_hooks().creating(t);
  };
  hooks.released = [&](const std::string& t) {
    EXPECT_EQ(outputs::temporaries_listed(), 1u);
    outputs::temporary_file_hooks().released(t);
  };
  float v[4] = {1, 2, 3, 4};
  weights::Writer w;
  w.add_f32("input", {4}, v);
  w.write(dir + "/w.safetensors", &hooks);
  ASSERT_EQ(seen.size(), 1u);
  EXPECT_EQ(seen[0].rfind(dir + "/w.safetensors.tmp-", 0), 0u) << seen[0];
  EXPECT_EQ(outputs::temporaries_listed(), 0u);
  EXPECT_EQ(folder_entries(dir), std::vector<std::string>{"w.safetensors"});
  EXPECT_EQ(weights::SafeTensors::load(dir + "/w.safetensors").f32("input")[3], 4.0f);
}

// SIGINT with temporaries on disk: they are removed, the old file stays, and the
// process dies of the signal. In a child, so the test process lives on.
TEST(OutputFiles, SigintRemovesTemporaries) {
  std::string dir = test_dir();
  write_text(dir + "/a.txt", "old a");
  for (int sig : {SIGINT, SIGTERM}) {
    pid_t pid = ::fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
      outputs::install_interrupt_cleanup();
      outputs::FileSet set;
      set.add(dir + "/a.txt", std::string("new a"));
      set.add(dir + "/b.txt", std::string("new b"));
      ::raise(sig);
      ::_exit(3);  // not reached
    }
    int status = 0;
    ASSERT_EQ(::waitpid(pid, &status, 0), pid);
    ASSERT_TRUE(WIFSIGNALED(status)) << status;
    EXPECT_EQ(WTERMSIG(status), sig);
    EXPECT_EQ(folder_entries(dir), std::vector<std::string>{"a.txt"});
    EXPECT_EQ(slurp(dir + "/a.txt"), "old a");
  }
}

// A signal ignored when the program starts (nohup, `cmd &` in a script) stays ignored.
TEST(OutputFiles, IgnoredSignalStaysIgnored) {
  std::string dir = test_dir();
  pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    ::signal(SIGHUP, SIG_IGN);
    outputs::install_interrupt_cleanup();
    outputs::FileSet set;
    set.add(dir + "/a.txt", std::string("a"));
    ::raise(SIGHUP);
    set.commit();
    ::_exit(0);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status)) << status;
  EXPECT_EQ(WEXITSTATUS(status), 0);
  EXPECT_EQ(slurp(dir + "/a.txt"), "a");
}

}  // namespace
