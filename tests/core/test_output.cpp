// core/output: a tool's output never deletes or overwrites what tactus did not write (issue:
// "tactus-solve s.toml -o mydata deleted thesis.tex"). Each test builds the situation on disk and
// checks both the refusal and that every user file is still there, byte for byte.
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

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

TEST(OutputFolder, RefusesItsOwnOutputOnceAUserAddedOrEditedAFile) {
  TempDir dir;
  make_output(dir / "results", "tactus-solve", {{"run.json", "1"}});
  write(dir / "results" / "notes.txt", "mine");
  expect_refusal([&] { OutputFolder(dir / "results", kSolve); }, "notes.txt");
  EXPECT_EQ(read(dir / "results" / "notes.txt"), "mine");

  make_output(dir / "results2", "tactus-solve", {{"run.json", "1"}});
  write(dir / "results2" / "run.json", "edited by hand");
  expect_refusal([&] { OutputFolder(dir / "results2", kSolve); }, "changed since");
  EXPECT_EQ(read(dir / "results2" / "run.json"), "edited by hand");
}

TEST(OutputFolder, ChecksAgainAtCommit) {
  TempDir dir;
  make_output(dir / "results", "tactus-solve", {{"run.json", "1"}});
  OutputFolder out(dir / "results", kSolve);
  write(dir / "results" / "notes.txt", "added while the run went on");
  write(out.path() / "run.json", "2");
  expect_refusal([&] { out.commit(); }, "notes.txt");
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

TEST(OutputFolder, RemovesStaleStagingOfDeadRunsOnly) {
  TempDir dir;
  // A staging folder left by a killed run: its marker names a process that has exited.
  const pid_t child = fork();
  if (child == 0) _exit(0);
  waitpid(child, nullptr, 0);
  const fs::path stale = dir / ("results.partial-" + std::to_string(child));
  write(stale / "run.json", "half");
  write(stale / tactus::kFolderMarker,
        R"({"tool": "tactus-solve", "state": "writing", "pid": )" + std::to_string(child) + R"(, "process_start": 1, "boot_id": "x"})");
  // One of a run still going (this process) and one of another tool: both kept.
  const fs::path other = dir / "results.partial-1";
  write(other / tactus::kFolderMarker, R"({"tool": "tactus-post", "state": "writing", "pid": 1, "process_start": 1, "boot_id": "x"})");
  {
    OutputFolder out(dir / "results", kSolve);
    EXPECT_FALSE(fs::exists(stale));
    EXPECT_TRUE(fs::exists(other));
  }
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
