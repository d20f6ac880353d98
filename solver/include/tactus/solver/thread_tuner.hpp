#pragma once
// The thread count of a run with run.threads = 0 (automatic), chosen while it goes: every so many
// steps the tuner times a few steps on all the threads and a few on one, interleaved, and keeps
// the faster until the next probe. The solver's sums do not depend on the thread count (fixed
// partitions, fixed order), so the choice changes no result, only the wall time. On a shared
// machine (another process busy on a core, CI, MPI ranks later) a thread that shares its core
// arrives late at every barrier, and all the threads can then be slower than one
// (docs/studies/shared-cores.md); on a quiet machine the probe costs about 1 % of the steps.
#include <cstddef>

namespace tactus::solver {

class ThreadTuner {
 public:
  // max_threads: the run's thread count; on = false keeps it fixed (a user's run.threads).
  ThreadTuner(int max_threads, bool on) : max_(max_threads), on_(on && max_threads > 1) {}
  int threads() const { return !on_ ? max_ : probing() ? (block_ % 2 == 0 ? max_ : 1) : chosen_; }
  // The wall time of the step just taken (on threads()); the tuner moves on.
  void step_took(double seconds) {
    if (!on_) return;
    if (!probing()) {
      if (++held_ >= kHoldSteps) held_ = 0, block_ = 0, in_block_ = 0, time_[0] = time_[1] = 0;
      return;
    }
    if (in_block_ > 0) time_[block_ % 2] += seconds;  // the block's first step waits for the threads to wake: left out
    if (++in_block_ == kBlockSteps) {
      in_block_ = 0;
      if (++block_ == 2 * kBlocks) {
        // All the threads must win by a margin: one thread is the safe choice on a shared machine,
        // where a preempted probe block makes the timings noisy.
        chosen_ = time_[0] < kMargin * time_[1] ? max_ : 1;
        chosen_one_ += chosen_ == 1;
        ++probes_;
      }
    }
  }
  // Probes made, and how many of them chose one thread.
  std::size_t probes() const { return probes_; }
  std::size_t probes_choosing_one() const { return chosen_one_; }

 private:
  static constexpr int kBlockSteps = 5, kBlocks = 3;  // 3 blocks of 5 steps per configuration, interleaved
  static constexpr int kHoldSteps = 1500;             // then the choice holds this many steps
  static constexpr double kMargin = 0.9;              // all threads kept only when 10 % faster than one
  bool probing() const { return block_ < 2 * kBlocks; }
  int max_;
  bool on_;
  int chosen_ = 0, block_ = 0, in_block_ = 0, held_ = 0;
  double time_[2] = {0, 0};  // all threads, one thread
  std::size_t probes_ = 0, chosen_one_ = 0;
};

}  // namespace tactus::solver
