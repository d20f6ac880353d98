// core/staged_output: a file is visible under its final name only after commit().
#include <gtest/gtest.h>

#include <fstream>

#include "tactus/core/error.hpp"
#include "tactus/core/staged_output.hpp"
#include "temp_dir.hpp"

using tactus::StagedOutput;
using tactus::testkit::TempDir;

TEST(StagedOutput, NothingLeftWhenNotCommitted) {
  TempDir dir;
  {
    StagedOutput out(dir / "result.txt");
    std::ofstream(out.path()) << "half";
    EXPECT_FALSE(std::filesystem::exists(dir / "result.txt"));
  }
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
}

TEST(StagedOutput, NeverReplacesAFolder) {
  TempDir dir;
  std::filesystem::create_directories(dir / "results");
  std::ofstream(dir / "results" / "old.vtu") << "old";
  StagedOutput out(dir / "results");
  std::ofstream(out.path()) << "new";
  EXPECT_THROW(out.commit(), tactus::WriteError);
  EXPECT_TRUE(std::filesystem::exists(dir / "results" / "old.vtu"));
}
