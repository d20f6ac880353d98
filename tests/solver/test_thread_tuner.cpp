// ThreadTuner (run.threads = 0) fed with made-up step times, so each rule is checked against a
// choice known in advance: the faster configuration wins, one preempted block cannot flip it (the
// sign test over interleaved pairs), short steps make longer blocks, and a confirmed choice holds
// longer.
#include <gtest/gtest.h>

#include <functional>

#include "tactus/solver/thread_tuner.hpp"

namespace {

using tactus::solver::ThreadTuner;

// Runs the tuner until it has made `probes` probes; cost(threads, step) is the step's wall time.
// Returns the steps taken.
int run_until(ThreadTuner& tuner, std::size_t probes, const std::function<double(int, int)>& cost) {
  int step = 0;
  while (tuner.probes() < probes) {
    tuner.step_took(cost(tuner.threads(), step));
    if (++step > 1000000) break;
  }
  return step;
}

TEST(ThreadTuner, KeepsAllThreadsOnlyWhenTheyAreFaster) {
  ThreadTuner quiet(2, true);
  run_until(quiet, 1, [](int n, int) { return n == 2 ? 1e-3 : 2e-3; });  // two threads halve the step
  EXPECT_EQ(quiet.threads(), 2);
  ThreadTuner shared(2, true);
  run_until(shared, 1, [](int n, int) { return n == 2 ? 1.6e-3 : 1e-3; });  // a busy neighbour: one thread wins
  EXPECT_EQ(shared.threads(), 1);
  EXPECT_EQ(shared.probes_choosing_one(), 1u);
  ThreadTuner close(2, true);
  run_until(close, 1, [](int n, int) { return n == 2 ? 0.95e-3 : 1e-3; });  // 5 % is inside the 10 % margin
  EXPECT_EQ(close.threads(), 1);
  ThreadTuner fixed(2, false);  // a user's run.threads: never probes
  run_until(fixed, 0, [](int, int) { return 1e-3; });
  for (int i = 0; i < 5000; ++i) fixed.step_took(1e-3);
  EXPECT_EQ(fixed.threads(), 2);
  EXPECT_EQ(fixed.probes(), 0u);
}

TEST(ThreadTuner, OnePreemptedBlockCannotFlipTheChoice) {
  // Equal step times on both, but the first one-thread block is preempted (3x slower). Summed over
  // the blocks, all threads would look 40 % faster and be kept; pair by pair they win only one pair.
  ThreadTuner tuner(2, true);
  int one_thread_blocks_seen = -1, last_threads = 0;
  run_until(tuner, 1, [&](int n, int) {
    if (n == 1 && last_threads != 1) ++one_thread_blocks_seen;
    last_threads = n;
    return n == 1 && one_thread_blocks_seen == 0 ? 3e-3 : 1e-3;
  });
  EXPECT_EQ(one_thread_blocks_seen, ThreadTuner::kBlocks - 1);
  EXPECT_EQ(tuner.threads(), 1);
}

TEST(ThreadTuner, ShortStepsMakeLongerBlocks) {
  // 0.1 ms steps: a block needs kBlockSeconds / 0.1 ms timed steps (40, or 41 where the sum of
  // forty 1e-4 falls short of 4e-3 by rounding) plus its untimed first step; 6 blocks per probe.
  ThreadTuner tuner(2, true);
  const int steps = run_until(tuner, 1, [](int, int) { return 1e-4; });
  std::printf("probe of 0.1 ms steps: %d steps (bounds %d..%d)\n", steps, 6 * 41, 6 * 42);
  EXPECT_GE(steps, 6 * 41);
  EXPECT_LE(steps, 6 * 42);
  // Long steps: the step count sets the block, kBlockSteps timed + 1.
  ThreadTuner slow(2, true);
  EXPECT_EQ(run_until(slow, 1, [](int, int) { return 1e-2; }), 6 * (ThreadTuner::kBlockSteps + 1));
}

TEST(ThreadTuner, AConfirmedChoiceHoldsLonger) {
  ThreadTuner tuner(2, true);
  const auto one_wins = [](int n, int) { return n == 2 ? 1.6e-3 : 1e-3; };
  int expected = ThreadTuner::kHoldSteps;
  for (std::size_t probe = 1; probe <= 7; ++probe) {
    run_until(tuner, probe, one_wins);
    EXPECT_EQ(tuner.hold_steps(), expected) << "after probe " << probe;
    expected = std::min(2 * expected, ThreadTuner::kMaxHoldSteps);
  }
  EXPECT_EQ(tuner.hold_steps(), ThreadTuner::kMaxHoldSteps);
  // The machine goes quiet: the next probe keeps all the threads and the hold drops back.
  run_until(tuner, 8, [](int n, int) { return n == 2 ? 1e-3 : 2e-3; });
  EXPECT_EQ(tuner.threads(), 2);
  EXPECT_EQ(tuner.hold_steps(), ThreadTuner::kHoldSteps);
}

}  // namespace
