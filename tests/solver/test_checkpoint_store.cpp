// solver/checkpoint: a checkpoint is its parts plus a manifest written last (CheckpointStore). The
// listing takes only complete ones (every part there, at its listed size), newest first; a write
// keeps the newest two and removes what no kept manifest lists; a checkpoint of several parts (a
// run of several processes, as MPI ranks will write) is complete only once its last part and the
// manifest are down.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "tactus/core/error.hpp"
#include "tactus/solver/checkpoint.hpp"
#include "temp_dir.hpp"

using namespace tactus;
using namespace tactus::solver;
using tactus::testkit::TempDir;
namespace fs = std::filesystem;

namespace {

StateArrays part_state(double value) {
  StateArrays s;
  s.kind = kCheckpointKind;
  s.reals["u"] = {value, 2 * value};
  return s;
}

std::size_t files_in(const fs::path& folder) {
  std::size_t n = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(folder)) ++n;
  return n;
}

}  // namespace

TEST(CheckpointStore, KeepsTheNewestTwoCompleteCheckpoints) {
  TempDir dir;
  const fs::path folder = dir.path() / "checkpoints";
  const CheckpointStore store(folder);
  for (std::size_t step : {10, 20, 30}) store.write(step, 1e-3 * static_cast<double>(step), part_state(static_cast<double>(step)));
  const std::vector<CheckpointListing> found = list_checkpoints(folder);
  std::printf("listed steps:");
  for (const auto& c : found) std::printf(" %zu (%zu part)", c.step, c.parts.size());
  std::printf("; files in the folder: %zu (expected 4: two parts, two manifests)\n", files_in(folder));
  ASSERT_EQ(found.size(), 2u);
  EXPECT_EQ(found[0].step, 30u);
  EXPECT_EQ(found[1].step, 20u);
  EXPECT_DOUBLE_EQ(found[0].time, 0.030);
  EXPECT_EQ(files_in(folder), 4u);
  EXPECT_EQ(read_state_file(found[0].parts[0], kCheckpointKind).reals.at("u")[1], 60.0);
}

TEST(CheckpointStore, APartWithoutItsManifestOrOfTheWrongSizeIsNotACheckpoint) {
  TempDir dir;
  const fs::path folder = dir.path() / "checkpoints";
  const CheckpointStore store(folder);
  store.write(10, 0.01, part_state(1));
  const fs::path manifest = store.write(20, 0.02, part_state(2));
  // A killed write: step 30's part is down, its manifest never came.
  write_state_file(folder / "checkpoint_000000000030.part0of1.h5", part_state(3));
  EXPECT_EQ(list_checkpoints(folder).front().step, 20u) << "a part without a manifest was listed";
  // Step 20's part cut short: its manifest no longer describes it, so step 10 is the newest.
  const fs::path part20 = list_checkpoints(folder).front().parts[0];
  fs::resize_file(part20, fs::file_size(part20) / 2);
  const std::vector<CheckpointListing> found = list_checkpoints(folder);
  std::printf("after a manifest-less step 30 and a truncated step 20: newest listed %zu, %zu listed\n", found.front().step, found.size());
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found.front().step, 10u);
  // A manifest of another kind is refused (warned about) and left out.
  std::ofstream(manifest) << R"({"kind": "something else", "step": 20, "time": 0.02, "parts": []})";
  EXPECT_EQ(list_checkpoints(folder).size(), 1u);
}

TEST(CheckpointStore, APartedCheckpointIsCompleteOnceEveryPartAndTheManifestAreDown) {
  TempDir dir;
  const fs::path folder = dir.path() / "checkpoints";
  // Part 1 of 2 first (another process's), then part 0, which writes the manifest.
  CheckpointStore(folder, 1, 2).write(40, 0.04, part_state(41));
  EXPECT_TRUE(list_checkpoints(folder).empty()) << "one part of two listed as a checkpoint";
  CheckpointStore(folder, 0, 2).write(40, 0.04, part_state(40));
  const std::vector<CheckpointListing> found = list_checkpoints(folder);
  ASSERT_EQ(found.size(), 1u);
  ASSERT_EQ(found[0].parts.size(), 2u);
  const double u0 = read_state_file(found[0].parts[0], kCheckpointKind).reals.at("u")[0];
  const double u1 = read_state_file(found[0].parts[1], kCheckpointKind).reals.at("u")[0];
  std::printf("two-part checkpoint of step %zu: part 0 holds %g, part 1 holds %g\n", found[0].step, u0, u1);
  EXPECT_EQ(u0, 40.0);
  EXPECT_EQ(u1, 41.0);
}

// A run over ranks writes one part per rank: each rank's nodes' per-node arrays, part 0 all else.
// Oracle: the whole state the parts were cut from, exactly; and the merge refuses parts whose
// nodes overlap or leave a node out, naming the part.
TEST(CheckpointParts, PartsCutByNodesMergeBackIntoTheWholeState) {
  const std::size_t nodes = 7;
  StateArrays whole;
  whole.kind = kCheckpointKind;
  for (std::size_t i = 0; i < 3 * nodes; ++i) whole.reals["integrator.u"].push_back(0.5 + static_cast<double>(i));
  for (std::size_t i = 0; i < nodes; ++i) whole.reals["integrator.nodal_mass"].push_back(10.0 + static_cast<double>(i));
  whole.reals["integrator.pressure_force"] = {};  // a run without follower pressures
  whole.reals["integrator.time"] = {0.25};
  whole.integers["integrator.step"] = {12};
  const std::vector<std::vector<std::uint32_t>> owned = {{0, 3, 6}, {1, 4}, {2, 5}};
  std::vector<StateArrays> parts;
  for (std::size_t k = 0; k < owned.size(); ++k) parts.push_back(checkpoint_part(whole, owned[k], nodes, k == 0));
  std::printf("part sizes (u values): %zu %zu %zu; part 1 holds the step: %d\n", parts[0].reals["integrator.u"].size(),
              parts[1].reals["integrator.u"].size(), parts[2].reals["integrator.u"].size(), int(parts[1].integers.count("integrator.step")));
  EXPECT_EQ(parts[1].reals.at("integrator.u").size(), 6u);
  EXPECT_EQ(parts[1].integers.count("integrator.step"), 0u);
  const std::vector<fs::path> files = {"part0", "part1", "part2"};
  const StateArrays merged = merge_checkpoint_parts(parts, files);
  EXPECT_EQ(merged.reals, whole.reals);
  EXPECT_EQ(merged.integers, whole.integers);
  // Node 4 in two parts (and so node 5 in none): refused, naming part 2.
  std::vector<StateArrays> overlapping = parts;
  overlapping[2] = checkpoint_part(whole, {2, 4}, nodes, false);
  try {
    merge_checkpoint_parts(overlapping, files);
    ADD_FAILURE() << "overlapping parts were merged";
  } catch (const InputError& e) {
    std::printf("overlapping parts: %s\n", e.what());
    EXPECT_NE(std::string(e.what()).find("part2"), std::string::npos);
  }
  // A part whose arrays do not hold its nodes' values: refused.
  std::vector<StateArrays> short_part = parts;
  short_part[1].reals["integrator.u"].pop_back();
  EXPECT_THROW(merge_checkpoint_parts(short_part, files), InputError);
}

// Part 0 of a run over ranks writes the manifest once the ranks have met; a part that is not in
// the folder then (a rank on another machine wrote it into a folder of its own) is a clear error,
// and no manifest is written.
TEST(CheckpointParts, AManifestWithAPartMissingIsRefused) {
  TempDir dir;
  const fs::path folder = dir.path() / "checkpoints";
  try {
    CheckpointStore(folder, 0, 2).write(10, 0.01, part_state(1), {}, 2, [] {});
    ADD_FAILURE() << "a manifest was written without part 1";
  } catch (const WriteError& e) {
    std::printf("part 1 missing: %s\n", e.what());
    EXPECT_NE(std::string(e.what()).find("part 1 of the checkpoint is not there"), std::string::npos);
  }
  EXPECT_TRUE(list_checkpoints(folder).empty());
  EXPECT_FALSE(fs::exists(folder / "checkpoint_000000000010.json"));
}
