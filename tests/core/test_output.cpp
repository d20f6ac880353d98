// core/output: a tool's output never deletes or overwrites what tactus did not write (issue:
// "tactus-solve s.toml -o mydata deleted thesis.tex"). Each test builds the situation on disk and
// checks both the refusal and that every user file is still there, byte for byte.
#include <fcntl.h>
#include <sys/file.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <csignal>
#include <fstream>
#include <sstream>

#include "tactus/core/error.hpp"
#include "tactus/core/output.hpp"
#include "temp_dir.hpp"

namespace fs = std::filesystem;
using tactus::OutputFiles;
using tactus::OutputFolder;
using tactus::OutputRules;
using tactus::WriteError;
using tactus::testkit::TempDir;

namespace {

std::string read(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

void write(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << text;
}

// One complete output of `tool` at `folder` holding `files` (relative name -> content).
void make_output(const fs::path& folder, const std::string& tool, std::map<std::string, std::string> files) {
  OutputFolder out(folder, {tool, {}, true});
  for (const auto& [name, text] : files) write(out.path() / name, text);
  out.commit();
}

// Expects a WriteError whose message contains `fragment`.
template <class F>
void expect_refusal(F&& f, const std::string& fragment) {
  try {
    f();
    FAIL() << "expected a refusal mentioning '" << fragment << "'";
  } catch (const WriteError& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

const OutputRules kSolve{"tactus-solve", {}, false};

}  // namespace

TEST(OutputFolder, NewFolderAppearsOnlyOnCommitWithItsMarker) {
  TempDir dir;
  {
    OutputFolder out(dir / "results", kSolve);
    write(out.path() / "run.json", "{}");
    write(out.path() / "results" / "state_0000.vtu", "x");
    EXPECT_FALSE(fs::exists(dir / "results"));
    out.commit();
  }
  EXPECT_EQ(read(dir / "results" / "run.json"), "{}");
  const std::string marker = read(dir / "results" / tactus::kFolderMarker);
  EXPECT_NE(marker.find("results/state_0000.vtu"), std::string::npos) << marker;
  EXPECT_NE(marker.find("tactus-solve"), std::string::npos);
}

TEST(OutputFolder, UncommittedLeavesNothing) {
  TempDir dir;
  { OutputFolder out(dir / "results", kSolve); }
  EXPECT_TRUE(fs::is_empty(dir.path()));
}

TEST(OutputFolder, RefusesAForeignFolderAndKeepsItsFiles) {
  TempDir dir;
  write(dir / "mydata" / "thesis.tex", "my thesis");
  expect_refusal([&] { OutputFolder(dir / "mydata", kSolve); }, "thesis.tex");
  expect_refusal([&] { OutputFolder(dir / "mydata", {"tactus-solve", {}, true}); }, "did not write");  // not even with --force
  EXPECT_EQ(read(dir / "mydata" / "thesis.tex"), "my thesis");
}

TEST(OutputFolder, AnEmptyFolderIsUsed) {
  TempDir dir;
  fs::create_directories(dir / "empty");
  OutputFolder out(dir / "empty", kSolve);
  write(out.path() / "run.json", "new");
  out.commit();
  EXPECT_EQ(read(dir / "empty" / "run.json"), "new");
}

TEST(OutputFolder, ReplacesItsOwnPreviousOutput) {
  TempDir dir;
  make_output(dir / "results", "tactus-solve", {{"old.vtu", "old"}, {"run.json", "1"}});
  OutputFolder out(dir / "results", kSolve);
  write(out.path() / "run.json", "2");
  out.commit();
  EXPECT_EQ(read(dir / "results" / "run.json"), "2");
  EXPECT_FALSE(fs::exists(dir / "results" / "old.vtu"));
  for (const auto& e : fs::directory_iterator(dir.path())) EXPECT_EQ(e.path().filename(), "results");  // no trash left
}

// A user's file, folder or link added to a previous output stays in place, byte for byte; a
// listed file whose content changed (by hash, even at the same size) makes the tool refuse.
TEST(OutputFolder, KeepsWhatAUserAddedAndRefusesAnEditedFile) {
  TempDir dir;
  make_output(dir / "results", "tactus-solve", {{"run.json", "1"}, {"results/state_0000.vtu", "old"}});
  write(dir / "results" / "notes.txt", "mine");
  fs::create_directories(dir / "results" / "my_empty");
  fs::create_directories(dir / "results" / "results" / "mine");
  fs::create_directory_symlink(dir.path(), dir / "results" / "link");
  {
    OutputFolder out(dir / "results", kSolve);
    write(out.path() / "run.json", "2");
    out.commit();
  }
  EXPECT_EQ(read(dir / "results" / "run.json"), "2");
  EXPECT_EQ(read(dir / "results" / "notes.txt"), "mine");
  EXPECT_TRUE(fs::is_directory(dir / "results" / "my_empty"));
  EXPECT_TRUE(fs::is_directory(dir / "results" / "results" / "mine"));
  EXPECT_TRUE(fs::is_symlink(dir / "results" / "link"));
  EXPECT_FALSE(fs::exists(dir / "results" / "results" / "state_0000.vtu"));                            // listed: replaced
  for (const auto& e : fs::directory_iterator(dir.path())) EXPECT_EQ(e.path().filename(), "results");  // no trash left

  make_output(dir / "results2", "tactus-solve", {{"run.json", "1"}});
  write(dir / "results2" / "run.json", "2");  // same size, other content: only the hash tells
  expect_refusal([&] { OutputFolder(dir / "results2", kSolve); }, "changed since");
  EXPECT_EQ(read(dir / "results2" / "run.json"), "2");
}

// A hand-written file that carries tactus's marker keys is not a manifest of this folder's files.
TEST(OutputFolder, AHandWrittenMarkerDoesNotMakeFilesTactus) {
  TempDir dir;
  write(dir / "mine" / "thesis.tex", "my thesis");
  write(dir / "mine" / tactus::kFolderMarker, R"({"tool": "tactus-solve", "state": "complete", "files": {"thesis.tex": {"size": 9, "hash": "0"}}})");
  expect_refusal([&] { OutputFolder(dir / "mine", kSolve); }, "changed since");
  EXPECT_EQ(read(dir / "mine" / "thesis.tex"), "my thesis");
}

TEST(OutputFolder, ChecksAgainAtCommit) {
  TempDir dir;
  make_output(dir / "results", "tactus-solve", {{"run.json", "1"}});
  OutputFolder out(dir / "results", kSolve);
  write(dir / "results" / "run.json", "edited while the run went on");
  write(dir / "results" / "notes.txt", "added while the run went on");
  write(out.path() / "run.json", "2");
  expect_refusal([&] { out.commit(); }, "run.json");
  EXPECT_EQ(read(dir / "results" / "run.json"), "edited while the run went on");
  EXPECT_EQ(read(dir / "results" / "notes.txt"), "added while the run went on");
}

TEST(OutputFolder, AnotherToolsOutputNeedsForce) {
  TempDir dir;
  make_output(dir / "out", "tactus-post", {{"summary.md", "report"}});
  expect_refusal([&] { OutputFolder(dir / "out", kSolve); }, "--force");
  EXPECT_EQ(read(dir / "out" / "summary.md"), "report");
  OutputFolder out(dir / "out", {"tactus-solve", {}, true});
  write(out.path() / "run.json", "x");
  out.commit();
  EXPECT_FALSE(fs::exists(dir / "out" / "summary.md"));
}

TEST(OutputFolder, RefusesTheCurrentFolderInputsAndTheirParents) {
  TempDir dir;
  write(dir / "case" / "s.toml", "scenario");
  const fs::path cwd = fs::current_path();
  fs::current_path(dir / "case");
  expect_refusal([&] { OutputFolder(".", kSolve); }, "current folder");
  fs::current_path(cwd);
  expect_refusal([&] { OutputFolder(dir / "case", {"tactus-solve", {dir / "case" / "s.toml"}, true}); }, "contains an input");
  expect_refusal([&] { OutputFolder(dir.path(), {"tactus-solve", {dir / "case" / "s.toml"}, true}); }, "contains an input");
  expect_refusal([&] { OutputFolder(dir / "case", {"tactus-post", {dir / "case"}, true}); }, "is an input");
  EXPECT_EQ(read(dir / "case" / "s.toml"), "scenario");
}

TEST(OutputFolder, PlacesThatCannotHoldAFolder) {
  TempDir dir;
  write(dir / "afile", "x");
  expect_refusal([&] { OutputFolder(dir / "afile", kSolve); }, "is a file");
  expect_refusal([&] { OutputFolder(dir / "afile" / "results", kSolve); }, "cannot create");
  expect_refusal([&] { OutputFolder("/proc/tactus-results", kSolve); }, "cannot");
  EXPECT_EQ(read(dir / "afile"), "x");
}

TEST(OutputFolder, RefusesWhenTheSpaceIsShort) {
  TempDir dir;
  OutputFolder out(dir / "results", kSolve);
  expect_refusal([&] { out.require_space(std::uintmax_t{1} << 62, "the results"); }, "free");
  out.require_space(1000, "the results");
}

// Staleness is the lock, never a process id: a staging folder whose lock file is free belongs to
// a process that is gone, whatever pid it records; one whose lock is held is alive, even if its
// recorded pid names no process here (another PID namespace). A killed run's staging with
// checkpoints is kept for --restart.
TEST(OutputFolder, StaleStagingIsJudgedByItsLockNotByAPid) {
  TempDir dir;
  const auto staging = [&](const std::string& token, const std::string& tool, bool checkpoints) {
    const fs::path p = dir / ("results.partial-" + token);
    write(p / "run.json", "half");
    write(p / tactus::kLockFile, "");
    write(p / tactus::kFolderMarker, R"({"tool": ")" + tool + R"(", "state": "writing", "token": ")" + token + R"(", "pid": )" +
                                         std::to_string(::getpid()) + R"(, "started_ns": 1})");
    if (checkpoints) write(p / tactus::kResumableDir / "c.h5", "x");
    return p;
  };
  const fs::path dead = staging("1-aaaa", "tactus-solve", false);      // records this very pid, yet its lock is free
  const fs::path resumable = staging("1-bbbb", "tactus-solve", true);  // a killed run with checkpoints
  const fs::path alive = staging("1-cccc", "tactus-post", false);      // its lock held by a child (another "namespace")
  int go[2];
  ASSERT_EQ(pipe(go), 0);
  const pid_t child = fork();
  if (child == 0) {
    const int fd = ::open((alive / tactus::kLockFile).c_str(), O_RDWR);
    ::flock(fd, LOCK_EX);
    char c = 0;
    (void)!::write(go[1], &c, 1);
    ::pause();
    _exit(0);
  }
  char c;
  ASSERT_EQ(::read(go[0], &c, 1), 1);
  {
    expect_refusal([&] { OutputFolder(dir / "results", kSolve); }, "writing this output right now");
    EXPECT_FALSE(fs::exists(dead));
    EXPECT_TRUE(fs::exists(resumable / tactus::kResumableDir / "c.h5"));
    EXPECT_TRUE(fs::exists(alive / "run.json"));
  }
  kill(child, SIGKILL);
  waitpid(child, nullptr, 0);
  OutputFolder out(dir / "results", kSolve);  // its lock is free now
  EXPECT_FALSE(fs::exists(alive));
}

// A process killed after its output was complete but before the swap: the next run publishes it.
TEST(OutputFolder, TheNextRunFinishesACommitAKilledRunLeft) {
  TempDir dir;
  make_output(dir / "results", "tactus-solve", {{"run.json", "old"}});
  write(dir / "results" / "notes.txt", "mine");
  // A killed swap (two-rename form): the new output at its place, naming the previous one aside.
  const fs::path aside = dir / "results.replaced-1-abcd";
  fs::rename(dir / "results", aside);
  make_output(dir / "results", "tactus-solve", {{"run.json", "new"}});
  {
    std::string m = read(dir / "results" / tactus::kFolderMarker);
    m.insert(m.find('{') + 1, R"("replaces": "results.replaced-1-abcd",)");
    write(dir / "results" / tactus::kFolderMarker, m);
  }
  OutputFolder next(dir / "results", kSolve);
  EXPECT_FALSE(fs::exists(aside));
  EXPECT_EQ(read(dir / "results" / "run.json"), "new");
  EXPECT_EQ(read(dir / "results" / "notes.txt"), "mine");
}

TEST(OutputFolder, NormalisesTheOutputPathBeforeAnyWork) {
  TempDir dir;
  fs::create_directories(dir / "real");
  fs::create_directory_symlink(dir / "real", dir / "link");
  {
    OutputFolder out((dir / "R").string() + "/", kSolve);  // trailing slash
    write(out.path() / "run.json", "1");
    out.commit();
  }
  EXPECT_EQ(read(dir / "R" / "run.json"), "1");
  {
    OutputFolder out(dir / "link" / "x", kSolve);  // a link in the parent
    write(out.path() / "run.json", "2");
    out.commit();
  }
  EXPECT_EQ(read(dir / "real" / "x" / "run.json"), "2");
  {
    OutputFolder out(dir / "a" / "missing" / ".." / "y", kSolve);  // '..' after a missing folder
    write(out.path() / "run.json", "3");
    out.commit();
  }
  EXPECT_EQ(read(dir / "a" / "y" / "run.json"), "3");
  expect_refusal([&] { OutputFolder(dir / "link", kSolve); }, "link");
  EXPECT_TRUE(fs::is_empty(dir / "real" / "x") == false);
}

TEST(OutputFiles, WritesTogetherAndRecordsThem) {
  TempDir dir;
  {
    OutputFiles out({dir / "block.msh", dir / "block.vtu"}, {"tactus-mesh", {}, false});
    write(out.staged(0), "msh");
    write(out.staged(1), "vtu");
    out.commit();
  }
  EXPECT_EQ(read(dir / "block.msh"), "msh");
  EXPECT_NE(read(dir / tactus::kFilesMarker).find("block.vtu"), std::string::npos);
  // The same tool may replace them; nothing else is left around.
  OutputFiles again({dir / "block.msh", dir / "block.vtu"}, {"tactus-mesh", {}, false});
  write(again.staged(0), "msh2");
  write(again.staged(1), "vtu2");
  again.commit();
  EXPECT_EQ(read(dir / "block.msh"), "msh2");
  std::size_t entries = 0;
  for (const auto& e : fs::directory_iterator(dir.path())) entries += e.is_regular_file();
  EXPECT_EQ(entries, 3u);
}

TEST(OutputFiles, NeverOverwritesAForeignOrEditedFile) {
  TempDir dir;
  write(dir / "mine.msh", "user mesh");
  expect_refusal([&] { OutputFiles({dir / "mine.msh"}, {"tactus-mesh", {}, true}); }, "did not write");
  EXPECT_EQ(read(dir / "mine.msh"), "user mesh");
  {
    OutputFiles out({dir / "b.msh"}, {"tactus-mesh", {}, false});
    write(out.staged(0), "tactus");
    out.commit();
  }
  write(dir / "b.msh", "edited");
  expect_refusal([&] { OutputFiles({dir / "b.msh"}, {"tactus-mesh", {}, false}); }, "changed since");
  EXPECT_EQ(read(dir / "b.msh"), "edited");
}

// After an upgrade: the pipeline once wrote `tactus-mesh -o mesh/` (a folder output) and now
// writes `-o mesh/mesh.msh` (file outputs). The files of the old folder output are tactus's, so
// the same tool replaces them; the folder's record follows, so the folder form still works too;
// a user's file there is still never touched.
TEST(OutputFiles, ReplaceTheFilesOfAnEarlierFolderOutput) {
  TempDir dir;
  make_output(dir / "mesh", "tactus-mesh", {{"mesh.msh", "old msh"}, {"mesh.vtu", "old vtu"}, {"quality.json", "{}"}});
  write(dir / "mesh" / "notes.txt", "mine");
  {
    OutputFiles out({dir / "mesh" / "mesh.msh", dir / "mesh" / "mesh.vtu"}, {"tactus-mesh", {}, false});
    write(out.staged(0), "new msh");
    write(out.staged(1), "new vtu");
    out.commit();
  }
  EXPECT_EQ(read(dir / "mesh" / "mesh.msh"), "new msh");
  EXPECT_EQ(read(dir / "mesh" / "notes.txt"), "mine");
  expect_refusal([&] { OutputFiles({dir / "mesh" / "notes.txt"}, {"tactus-mesh", {}, true}); }, "did not write");
  expect_refusal([&] { OutputFiles({dir / "mesh" / "mesh.msh"}, {"tactus-solve", {}, false}); }, "--force");
  fs::remove(dir / "mesh" / "notes.txt");
  OutputFolder again(dir / "mesh", {"tactus-mesh", {}, false});  // the folder form: its record is current
  write(again.path() / "mesh.msh", "folder msh");
  again.commit();
  EXPECT_EQ(read(dir / "mesh" / "mesh.msh"), "folder msh");
}
