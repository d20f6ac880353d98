#include "tactus/core/log.hpp"

#include <atomic>
#include <iostream>
#include <mutex>

namespace tactus::log {

namespace {
std::atomic<Level> g_level{Level::info};
std::mutex g_mutex;
}  // namespace

void set_level(Level lvl) { g_level = lvl; }
Level level() { return g_level; }

void write(Level lvl, const std::string& message) {
  if (lvl > g_level.load() || message.empty()) return;
  std::lock_guard lock(g_mutex);
  std::cerr << message << '\n';
}

void warn(const std::string& message) {
  if (g_level.load() == Level::quiet) return;
  std::lock_guard lock(g_mutex);
  std::cerr << "warning: " << message << '\n';
}

}  // namespace tactus::log
