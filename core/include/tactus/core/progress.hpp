#pragma once
// Progress of a long loop: on a terminal, one self-overwriting line with count, rate, ETA and a
// stage-specific note (e.g. simulated time); when stderr is not a terminal (logs, CI) it stays
// quiet and only `finish` writes one summary line at verbose level.
#include <chrono>
#include <cstddef>
#include <string>

namespace tactus {

class Progress {
 public:
  Progress(std::string label, std::size_t total);
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  // Cheap to call every iteration: redraws at most ~10 times a second.
  void update(std::size_t done, const std::string& note = {});
  // Whether update() would redraw now (so a caller builds its note only then).
  bool due() const;
  void finish(const std::string& note = {});
  double elapsed_seconds() const;

  // Forces the terminal behaviour on or off (tests, TACTUS_PROGRESS=0/1).
  static void set_enabled(bool enabled);

 private:
  std::string label_;
  std::size_t total_;
  std::chrono::steady_clock::time_point start_, last_draw_;
  bool drawn_ = false, finished_ = false, tty_;
};

}  // namespace tactus
