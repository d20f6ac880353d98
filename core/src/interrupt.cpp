#include "tactus/core/interrupt.hpp"

#include <pthread.h>
#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <mutex>
#include <set>
#include <thread>

namespace tactus {

namespace {

std::atomic<int> g_signal{0};
std::atomic<bool> g_handled{false};  // the main thread caught Interrupted and is exiting
std::mutex g_mutex;
std::set<std::filesystem::path>& staging_paths() {
  static std::set<std::filesystem::path> paths;
  return paths;
}

const char* signal_name(int s) {
  switch (s) {
    case SIGINT:
      return "SIGINT";
    case SIGTERM:
      return "SIGTERM";
    case SIGHUP:
      return "SIGHUP";
    default:
      return "signal";
  }
}

// Removes every registered staging path, says so, and ends the process.
[[noreturn]] void end_process(const std::string& program, int s) {
  {
    std::lock_guard lock(g_mutex);
    for (const auto& p : staging_paths()) {
      std::error_code ec;
      std::filesystem::remove_all(p, ec);
    }
  }
  std::fprintf(stderr, "%s: interrupted (%s); partial output removed\n", program.c_str(), signal_name(s));
  std::fflush(stderr);
  _exit(128 + s);
}

}  // namespace

Interrupted::Interrupted(int s) : Error(std::string("interrupted (") + signal_name(s) + "); partial output removed"), signal_(s) {}
Interrupted::Interrupted(int s, const std::string& what_was_kept)
    : Error(std::string("interrupted (") + signal_name(s) + "); " + what_was_kept), signal_(s) {}

bool interrupt_requested() noexcept { return g_signal.load(std::memory_order_relaxed) != 0; }

void check_interrupt() {
  if (const int s = g_signal.load(std::memory_order_relaxed)) throw Interrupted(s);
}

void request_interrupt_for_testing(int s) { g_signal = s; }

void mark_interrupt_handled() noexcept { g_handled = true; }

void unblock_stop_signals() noexcept {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGTERM);
  sigaddset(&set, SIGHUP);
  pthread_sigmask(SIG_UNBLOCK, &set, nullptr);
}

void register_staging_path(const std::filesystem::path& path) {
  std::lock_guard lock(g_mutex);
  staging_paths().insert(path);
}

void unregister_staging_path(const std::filesystem::path& path) {
  std::lock_guard lock(g_mutex);
  staging_paths().erase(path);
}

void install_interrupt_handling(const std::string& program, double grace_seconds) {
  static std::once_flag once;
  std::call_once(once, [&] {
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGINT);
    sigaddset(&set, SIGTERM);
    sigaddset(&set, SIGHUP);
    pthread_sigmask(SIG_BLOCK, &set, nullptr);
    std::thread([set, program, grace_seconds] {
      int s = 0;
      if (sigwait(&set, &s) != 0) return;
      g_signal = s;
      // The main thread gets the grace period to unwind by itself; a second signal, or the end of
      // the grace period, ends the process from here.
      timespec wait{static_cast<time_t>(grace_seconds), static_cast<long>((grace_seconds - static_cast<time_t>(grace_seconds)) * 1e9)};
      siginfo_t info;
      if (sigtimedwait(&set, &info, &wait) > 0) s = info.si_signo;
      // The main thread is already on its way out with its own message: give it a moment more.
      for (int i = 0; i < 50 && g_handled; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(100));
      end_process(program, s);
    }).detach();
  });
}

}  // namespace tactus
