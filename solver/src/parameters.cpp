#include "tactus/solver/parameters.hpp"

#include <cmath>
#include <sstream>

namespace tactus::solver {

namespace {
std::string fmt(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}
}  // namespace

std::string ValueSpec::range_text() const {
  const bool lo = std::isfinite(min), hi = std::isfinite(max);
  if (!lo && !hi) return "";
  if (lo && !hi) return std::string(min_exclusive ? "> " : ">= ") + fmt(min);
  if (!lo && hi) return std::string(max_exclusive ? "< " : "<= ") + fmt(max);
  return std::string(min_exclusive ? "(" : "[") + fmt(min) + ", " + fmt(max) + (max_exclusive ? ")" : "]");
}

bool ValueSpec::in_range(double v) const {
  if (!std::isfinite(v)) return false;
  if (min_exclusive ? !(v > min) : !(v >= min)) return false;
  if (max_exclusive ? !(v < max) : !(v <= max)) return false;
  return true;
}

const ValueSpec* SectionSpec::find(const std::string& key) const {
  for (const auto& k : keys)
    if (k.key == key) return &k;
  return nullptr;
}

ValueSpec number(std::string key, std::string unit, std::string doc, double min, bool min_exclusive, double max, bool max_exclusive) {
  ValueSpec s;
  s.key = std::move(key);
  s.unit = std::move(unit);
  s.doc = std::move(doc);
  s.min = min;
  s.min_exclusive = min_exclusive;
  s.max = max;
  s.max_exclusive = max_exclusive;
  s.required = true;
  return s;
}

}  // namespace tactus::solver
