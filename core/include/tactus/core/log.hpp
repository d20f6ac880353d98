#pragma once
// Minimal levelled logging to stderr. Stages log what they do at `info`, details at `verbose`.
#include <sstream>
#include <string>

namespace tactus::log {

enum class Level { quiet = 0, info = 1, verbose = 2, debug = 3 };

void set_level(Level level);
Level level();
void write(Level level, const std::string& message);

// Stream-style helpers: log::info() << "meshed " << n << " tets";  (flushed at end of statement)
class Line {
 public:
  explicit Line(Level lvl) : level_(lvl) {}
  Line(const Line&) = delete;
  Line& operator=(const Line&) = delete;
  ~Line() { write(level_, stream_.str()); }
  template <class T>
  Line& operator<<(const T& v) {
    if (level_ <= level()) stream_ << v;
    return *this;
  }

 private:
  Level level_;
  std::ostringstream stream_;
};

inline Line info() { return Line(Level::info); }
inline Line verbose() { return Line(Level::verbose); }
inline Line debug() { return Line(Level::debug); }
void warn(const std::string& message);  // always shown unless quiet

}  // namespace tactus::log
