#pragma once
// The thread count of a run with run.threads = 0 (automatic), chosen while it goes: every so many
// steps the tuner times a few blocks of steps on all the threads and as many on one, interleaved,
// and keeps the faster until the next probe. The solver's sums do not depend on the thread count
// (fixed partitions, fixed order), so the choice changes no result, only the wall time. On a shared
// machine (another process busy on a core, CI, MPI ranks later) a thread that shares its core
// arrives late at every barrier, and all the threads can then be slower than one
// (docs/studies/shared-cores.md).
//
// Three rules keep a noisy machine from misleading it:
// - a block lasts at least kBlockSteps steps and kBlockSeconds of wall time, so a block of short
//   steps (the contact sweep, ~0.1 ms) spans a few scheduler slices instead of landing in one;
// - all the threads are kept only when they win every interleaved pair by the margin (a sign test:
//   one pair that a preempted one-thread block lost by chance cannot flip the choice);
// - a choice that a probe confirms holds twice as long next time (up to kMaxHoldSteps), so a
//   steady machine pays for fewer probes; a changed choice drops the hold back to kHoldSteps.
#include <algorithm>
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
      if (++held_ >= hold_) held_ = 0, block_ = 0, start_block();
      return;
    }
    // The block's first step waits for the threads to wake (passive waiting): left out.
    if (in_block_++ > 0) block_seconds_ += seconds;
    if (in_block_ > kBlockSteps && (block_seconds_ >= kBlockSeconds || in_block_ >= kMaxBlockSteps)) end_block();
  }
  // Probes made, and how many of them chose one thread.
  std::size_t probes() const { return probes_; }
  std::size_t probes_choosing_one() const { return chosen_one_; }
  // Steps the current choice holds before the next probe.
  int hold_steps() const { return hold_; }

  static constexpr int kBlockSteps = 5;          // timed steps per block at least
  static constexpr int kMaxBlockSteps = 200;     // and at most, however short the steps
  static constexpr double kBlockSeconds = 4e-3;  // a few of Linux's scheduler slices (~3 ms)
  static constexpr int kBlocks = 3;              // blocks per configuration, interleaved
  static constexpr int kHoldSteps = 1500;        // a changed choice holds this many steps
  static constexpr int kMaxHoldSteps = 24000;    // a confirmed one, doubling, up to this
  static constexpr double kMargin = 0.9;         // all threads kept only when 10 % faster than one, in every pair

 private:
  bool probing() const { return block_ < 2 * kBlocks; }
  void start_block() { in_block_ = 0, block_seconds_ = 0; }
  void end_block() {
    per_step_[block_] = block_seconds_ / (in_block_ - 1);
    start_block();
    if (++block_ < 2 * kBlocks) return;
    bool all_win = true;
    for (int pair = 0; pair < kBlocks; ++pair) all_win = all_win && per_step_[2 * pair] < kMargin * per_step_[2 * pair + 1];
    const int choice = all_win ? max_ : 1;
    hold_ = probes_ > 0 && choice == chosen_ ? std::min(2 * hold_, kMaxHoldSteps) : kHoldSteps;
    chosen_ = choice;
    chosen_one_ += chosen_ == 1;
    ++probes_;
  }
  int max_;
  bool on_;
  int chosen_ = 0, block_ = 0, in_block_ = 0, held_ = 0, hold_ = kHoldSteps;
  double block_seconds_ = 0;
  double per_step_[2 * kBlocks] = {};  // seconds per step of each block: even all threads, odd one thread
  std::size_t probes_ = 0, chosen_one_ = 0;
};

}  // namespace tactus::solver
