#pragma once
// Declarations of every user-settable value (scenario keys, material parameters) with its unit
// and valid range. The scenario reader validates against these, and `tactus-solve keys` prints
// the reference in docs/scenario-reference.md from the very same declarations.
#include <limits>
#include <string>
#include <vector>

namespace tactus::solver {

enum class ValueType { number, integer, boolean, string, vec3, number_list, vec3_list, table, table_list };

struct ValueSpec {
  std::string key;
  ValueType type = ValueType::number;
  std::string unit;  // SI unit, "" when dimensionless or not a number
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  bool min_exclusive = false, max_exclusive = false;
  bool required = false;
  std::string default_text;  // shown in the reference; empty when required or none
  std::string doc;
  std::vector<std::string> choices;  // an enumeration's values as written in the file (empty: not one)

  // "> 0", "[0, 0.5)", ... or "" when unbounded.
  std::string range_text() const;
  bool in_range(double v) const;
};

struct SectionSpec {
  std::string name;  // as in the file: "run", "bodies", "materials.<name> (hgo)", ...
  std::string doc;
  std::vector<ValueSpec> keys;
  const ValueSpec* find(const std::string& key) const;
};

// The values an enumeration key takes, as written in the file, with what each means (the
// scenario reader binds them to enum members, scenario_keys.hpp; a material its formulation).
template <class E>
struct Choice {
  E value;
  const char* name;
  const char* doc;
};

template <class E>
std::string name_of(E value, const std::vector<Choice<E>>& choices) {
  for (const Choice<E>& c : choices)
    if (c.value == value) return c.name;
  return "";
}

// Convenience builders for the declaration tables.
ValueSpec number(std::string key, std::string unit, std::string doc, double min = -std::numeric_limits<double>::infinity(),
                 bool min_exclusive = false, double max = std::numeric_limits<double>::infinity(), bool max_exclusive = false);

}  // namespace tactus::solver
