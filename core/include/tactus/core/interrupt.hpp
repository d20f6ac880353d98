#pragma once
// Clean stops on SIGINT / SIGTERM / SIGHUP. Every tactus executable calls
// `install_interrupt_handling()` first thing (cli::run does): the signals are blocked in every
// thread and taken by one watcher thread, which raises a flag. Long loops call
// `check_interrupt()` (Progress::update does), which throws `Interrupted`; the stack unwinds,
// staged outputs remove themselves and the tool exits with 128 + signal. When the main thread is
// inside third-party code that never returns to such a check (a CGAL refinement, say) the watcher
// removes every registered staging path itself after a short grace period and ends the process
// with the same exit code, so an interrupted tool never leaves a half-written output behind.
#include <filesystem>
#include <string>

#include "tactus/core/error.hpp"

namespace tactus {

class Interrupted : public Error {
 public:
  explicit Interrupted(int signal_number);
  // When the tool kept something on purpose (a run's checkpoint): says what instead of "partial output removed".
  Interrupted(int signal_number, const std::string& what_was_kept);
  int signal_number() const noexcept { return signal_; }
  int exit_code() const noexcept { return 128 + signal_; }

 private:
  int signal_;
};

// Call before any other thread exists (OpenMP pools inherit the blocked signals).
// `grace_seconds`: how long the main thread gets to stop by itself.
void install_interrupt_handling(const std::string& program, double grace_seconds = 3.0);

// True once a stop signal arrived (an atomic load: cheap in hot loops).
bool interrupt_requested() noexcept;
// Throws Interrupted when a stop signal arrived.
void check_interrupt();
// cli::run calls this when it caught Interrupted and is about to exit by itself.
void mark_interrupt_handled() noexcept;
// For tests: raise or clear the flag as the watcher would.
void request_interrupt_for_testing(int signal_number);

// A forked child that execs another program calls this first: the blocked stop signals would
// otherwise be inherited, and the program could never be stopped (exec keeps the signal mask).
void unblock_stop_signals() noexcept;

// Staging paths removed by the watcher when it has to end the process itself.
void register_staging_path(const std::filesystem::path& path);
void unregister_staging_path(const std::filesystem::path& path);

}  // namespace tactus
