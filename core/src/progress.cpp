#include "tactus/core/progress.hpp"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <optional>

#include "tactus/core/interrupt.hpp"
#include "tactus/core/log.hpp"

namespace tactus {

namespace {
std::optional<bool> g_forced;

bool terminal_progress() {
  if (g_forced) return *g_forced;
  if (const char* env = std::getenv("TACTUS_PROGRESS")) return env[0] == '1';
  return isatty(STDERR_FILENO) == 1;
}

std::string format_duration(double s) {
  char buf[32];
  if (s < 60)
    std::snprintf(buf, sizeof buf, "%.1fs", s);
  else if (s < 3600)
    std::snprintf(buf, sizeof buf, "%dm%02ds", static_cast<int>(s / 60), static_cast<int>(s) % 60);
  else
    std::snprintf(buf, sizeof buf, "%dh%02dm", static_cast<int>(s / 3600), static_cast<int>(s / 60) % 60);
  return buf;
}
}  // namespace

void Progress::set_enabled(bool enabled) { g_forced = enabled; }

Progress::Progress(std::string label, std::size_t total)
    : label_(std::move(label)),
      total_(total),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_),
      tty_(terminal_progress() && log::level() != log::Level::quiet) {}

Progress::~Progress() {
  if (drawn_ && !finished_) std::fputc('\n', stderr);
}

double Progress::elapsed_seconds() const { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count(); }

bool Progress::due() const { return tty_ && (!drawn_ || std::chrono::steady_clock::now() - last_draw_ >= std::chrono::milliseconds(100)); }

void Progress::update(std::size_t done, const std::string& note) {
  check_interrupt();  // long loops report progress: the natural place to stop on Ctrl-C
  if (!tty_) return;
  const auto now = std::chrono::steady_clock::now();
  if (drawn_ && now - last_draw_ < std::chrono::milliseconds(100)) return;
  last_draw_ = now;
  drawn_ = true;
  const double t = elapsed_seconds();
  const double rate = t > 0 ? static_cast<double>(done) / t : 0.0;
  const double frac = total_ ? static_cast<double>(done) / static_cast<double>(total_) : 0.0;
  const double eta = rate > 0 && done < total_ ? static_cast<double>(total_ - done) / rate : 0.0;
  std::fprintf(stderr, "\r%s %zu/%zu (%.0f%%) %.3g/s elapsed %s ETA %s %s\033[K", label_.c_str(), done, total_, 100.0 * frac, rate,
               format_duration(t).c_str(), format_duration(eta).c_str(), note.c_str());
  std::fflush(stderr);
}

void Progress::finish(const std::string& note) {
  if (finished_) return;
  finished_ = true;
  const std::string line = label_ + " done in " + format_duration(elapsed_seconds()) + (note.empty() ? "" : " " + note);
  if (drawn_) {
    std::fprintf(stderr, "\r%s\033[K\n", line.c_str());
  } else {
    log::verbose() << line;
  }
}

}  // namespace tactus
